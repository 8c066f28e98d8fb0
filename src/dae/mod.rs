//! The DAE layer: the [`Dae`] trait, the sparse linear solvers and the integrators that
//! see only that trait.
//!
//! A fully implicit system `F(t, y, ẏ) = 0` of size n is described by
//! - its residual F;
//! - the fixed sparsity pattern of the iteration matrix `J = ∂F/∂y + cj ∂F/∂ẏ` and a
//!   routine that fills J's values (in that pattern's order) for a given `cj`;
//! - which components are differential (ẏ appears) and which algebraic;
//! - consistent initial values (y₀, ẏ₀);
//! - the breakpoints where the forcing has a kink, so that no step straddles one.
//!
//! The residual (or Jacobian) may report an inadmissible state ([`DaeError::Inadmissible`],
//! e.g. an inverted element), which the integrators treat as a recoverable failure: the
//! step is cut and retried.
//!
//! Two integrators implement [`Integrator`]: SUNDIALS IDA ([`crate::sundials::Ida`],
//! variable order and step) and the fixed-step [`bdf2::Bdf2`] that verifies it. Both use
//! the same [`linsolve::LinearSolver`] (faer's sparse LU by default, SUNDIALS' KLU as an
//! alternative, or [`condensed::CondensedLu`], which eliminates the velocities of a
//! first-order (u, v) system and factorizes the half-size system).

pub mod bdf2;
pub mod condensed;
pub mod linsolve;
pub mod nonlinear;
pub mod problems;
pub mod sensitivity;
pub mod timing;

use faer::sparse::SymbolicSparseColMat;
use nonlinear::NewtonCounts;
use serde::{Deserialize, Serialize};

pub use linsolve::{LinearSolver, LinearSolverFactory, SharedFactory};

/// The sparsity pattern of the iteration matrix (compressed sparse columns, row indices
/// sorted within each column). Values handed to [`Dae::jacobian`] follow its order.
pub type Pattern = SymbolicSparseColMat<usize>;

/// A recoverable or fatal failure reported by the problem itself.
#[derive(Debug, Clone, thiserror::Error)]
pub enum DaeError {
    /// The state cannot be evaluated (e.g. an element with det F ≤ 0). Recoverable: the
    /// integrator cuts its step.
    #[error("inadmissible state: {0}")]
    Inadmissible(Inadmissible),
    /// Anything else: the integration stops.
    #[error("{0}")]
    Fatal(String),
}

/// Why a state cannot be evaluated, as fields a caller can classify (a sweep's failure
/// map, the integrators' messages).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Inadmissible {
    /// A finite element turned inside out, or flattened, at one of its points: `quantity`
    /// (`det F`, or the hoop stretch `1 + u_r/r`) is `value ≤ 0` there.
    #[error("element {element}, {point}: {quantity} = {value:.3e}")]
    Element {
        /// Time of the residual that met it \[s\] (NaN where not known).
        t: f64,
        /// Index of the element in the mesh.
        element: usize,
        /// The point of the element.
        point: ElementPoint,
        /// What is not positive.
        quantity: &'static str,
        /// Its value.
        value: f64,
    },
    /// Some entry of the residual or of the iteration matrix is not finite.
    #[error("non-finite {0}")]
    NonFinite(&'static str),
    /// Any other reason (test problems).
    #[error("{0}")]
    Other(String),
}

impl Inadmissible {
    /// The same reason, at time `t` when it concerns an element.
    pub fn at(self, t_now: f64) -> Self {
        match self {
            Inadmissible::Element {
                element,
                point,
                quantity,
                value,
                ..
            } => Inadmissible::Element {
                t: t_now,
                element,
                point,
                quantity,
                value,
            },
            other => other,
        }
    }
}

/// A point of a finite element where the state is evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ElementPoint {
    /// Point `q` of the standard (solid and mass) rule.
    Quadrature(usize),
    /// Point `q` of the contact and adhesion band's rule.
    Contact(usize),
}

impl std::fmt::Display for ElementPoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ElementPoint::Quadrature(q) => write!(f, "quadrature point {q}"),
            ElementPoint::Contact(q) => write!(f, "contact point {q}"),
        }
    }
}

/// A state (t, y, ẏ) of a DAE.
#[derive(Debug, Clone, Copy)]
pub struct State<'a> {
    /// Time.
    pub t: f64,
    /// y.
    pub y: &'a [f64],
    /// ẏ.
    pub yp: &'a [f64],
}

impl<'a> State<'a> {
    /// The state (t, y, ẏ).
    #[inline]
    pub fn new(t: f64, y: &'a [f64], yp: &'a [f64]) -> Self {
        State { t, y, yp }
    }
}

/// A fully implicit DAE `F(t, y, ẏ) = 0`: the only thing integrators see.
pub trait Dae {
    /// Number of unknowns n.
    fn size(&self) -> usize;

    /// Residual `r = F(t, y, ẏ)` at `at`.
    fn residual(&mut self, at: State, r: &mut [f64]) -> Result<(), DaeError>;

    /// The pattern of `J = ∂F/∂y + cj ∂F/∂ẏ`, fixed for the run.
    fn pattern(&self) -> &Pattern;

    /// Fills `values` (length `pattern().compute_nnz()`, the pattern's order) with
    /// `J = ∂F/∂y + cj ∂F/∂ẏ` at `at`. Every value must be written (not accumulated).
    fn jacobian(&mut self, at: State, cj: f64, values: &mut [f64]) -> Result<(), DaeError>;

    /// For each component: `true` if differential (ẏᵢ appears in F), `false` if algebraic.
    fn differential(&self) -> Vec<bool>;

    /// Consistent initial values `(t₀, y₀, ẏ₀)`.
    fn initial(&self) -> (f64, Vec<f64>, Vec<f64>);

    /// Called by the integrators after each accepted step with the state at its end, for
    /// quantities integrated beside the system. Default: nothing.
    fn accepted_step(&mut self, _t: f64, _y: &[f64], _yp: &[f64]) {}

    /// Times where the forcing has a kink (phase boundaries). Integrators stop exactly there.
    fn breakpoints(&self) -> Vec<f64> {
        Vec::new()
    }

    /// The (position, velocity) pairs of a second-order system written in first-order
    /// form, if it has them: see [`FirstOrderBlocks`]. A linear solver may use them to
    /// eliminate the velocities ([`condensed::CondensedLu`]). Default: none.
    fn first_order_blocks(&self) -> Option<FirstOrderBlocks> {
        None
    }

    /// Root functions `g(t, y, ẏ)` whose zeros the integrators locate (MODEL.md §11, the
    /// phases the cell starts itself): one entry per function, the direction of a crossing
    /// that counts (+1 rising through 0, −1 falling, 0 either). Default: none.
    fn root_directions(&self) -> Vec<i32> {
        Vec::new()
    }

    /// `g_i(t, y, ẏ)` into `g` (length `root_directions().len()`), continuous in t along
    /// the solution. Default: nothing.
    fn root_functions(&mut self, _at: State, _g: &mut [f64]) -> Result<(), DaeError> {
        Ok(())
    }
}

/// A boxed DAE is the DAE it holds (a run's model behind a trait object).
impl<T: Dae + ?Sized> Dae for Box<T> {
    fn size(&self) -> usize {
        (**self).size()
    }
    fn residual(&mut self, at: State, r: &mut [f64]) -> Result<(), DaeError> {
        (**self).residual(at, r)
    }
    fn pattern(&self) -> &Pattern {
        (**self).pattern()
    }
    fn jacobian(&mut self, at: State, cj: f64, v: &mut [f64]) -> Result<(), DaeError> {
        (**self).jacobian(at, cj, v)
    }
    fn differential(&self) -> Vec<bool> {
        (**self).differential()
    }
    fn initial(&self) -> (f64, Vec<f64>, Vec<f64>) {
        (**self).initial()
    }
    fn accepted_step(&mut self, t: f64, y: &[f64], yp: &[f64]) {
        (**self).accepted_step(t, y, yp)
    }
    fn breakpoints(&self) -> Vec<f64> {
        (**self).breakpoints()
    }
    fn first_order_blocks(&self) -> Option<FirstOrderBlocks> {
        (**self).first_order_blocks()
    }
    fn root_directions(&self) -> Vec<i32> {
        (**self).root_directions()
    }
    fn root_functions(&mut self, at: State, g: &mut [f64]) -> Result<(), DaeError> {
        (**self).root_functions(at, g)
    }
}

/// A DAE `F(t, y, ẏ; p) = 0` on parameters `p₁ … p_m` whose forward sensitivities
/// `sᵢ = ∂y/∂pᵢ` an integrator can carry beside the solution (SUNDIALS IDAS): each solves
/// the linear DAE `F_y sᵢ + F_ẏ ṡᵢ + F_{pᵢ} = 0` along the solution.
pub trait SensitivityDae: Dae {
    /// The number of parameters m.
    fn parameter_count(&self) -> usize;

    /// The sensitivity residuals `out[i] = F_y s[i] + F_ẏ sp[i] + F_{pᵢ}` at `at`, where
    /// `r = F(at)` (the residual the integrator has just evaluated there).
    fn sensitivity_residuals(
        &mut self,
        at: State,
        r: &[f64],
        s: &[&[f64]],
        sp: &[&[f64]],
        out: &mut [&mut [f64]],
    ) -> Result<(), DaeError>;

    /// Consistent initial sensitivities `(sᵢ(t₀), ṡᵢ(t₀))`, one pair of vectors per
    /// parameter: the derivatives of [`Dae::initial`]'s `y₀`, `ẏ₀` with respect to pᵢ.
    fn initial_sensitivities(&self) -> (Vec<Vec<f64>>, Vec<Vec<f64>>);
}

/// A zero of the DAE's root functions ([`Dae::root_directions`]) that an integrator
/// stopped at.
#[derive(Debug, Clone, PartialEq)]
pub struct Root {
    /// Its time, to the integrator's root tolerance.
    pub t: f64,
    /// Per function, as IDA's `rootsfound`: +1 rising through zero here, −1 falling, 0 not
    /// crossing.
    pub crossings: Vec<i32>,
}

impl Root {
    /// The root at `t` of the functions with these crossings (+1, −1 or 0 each).
    pub fn new(t: f64, crossings: Vec<i32>) -> Self {
        Root { t, crossings }
    }

    /// The functions that crossed zero there (indices into [`Dae::root_directions`]).
    pub fn functions(&self) -> Vec<usize> {
        (0..self.crossings.len())
            .filter(|&i| self.crossings[i] != 0)
            .collect()
    }
}

/// Whether `g` going from `g0` to `g1` crosses zero in `direction` (+1 rising, −1
/// falling, 0 either), the rule of IDA's root finding (a zero at the end counts).
pub fn crosses(g0: f64, g1: f64, direction: i32) -> bool {
    let rising = g0 < 0.0 && g1 >= 0.0;
    let falling = g0 > 0.0 && g1 <= 0.0;
    (rising && direction >= 0) || (falling && direction <= 0)
}

/// The kinematic structure of a second-order system written in first order: pairs
/// (p, q) of unknowns where row p of F is the kinematic equation `ẏ_p − y_q = 0`, so that
/// row p of `J = ∂F/∂y + cj ∂F/∂ẏ` has exactly two entries, `J_pp = cj` and
/// `J_pq = −1` (any nonzero `J_pq` and any `J_pp` are accepted: they are read from J's
/// values at each factorization), and row q is the second-order (momentum) equation of
/// the same component.
///
/// With y = (u, v, μ), the cell model's J is `[[cj·I, −I, 0], [K, cj·M + C, B],
/// [R_u, 0, cj·I − R_μ]]` and the pairs are (u_k, v_k).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FirstOrderBlocks {
    /// The pairs `[p, q]`: p the position unknown (and kinematic row), q its velocity
    /// unknown (and momentum row). Every index appears at most once over all pairs.
    pub pairs: Vec<[usize; 2]>,
}

impl FirstOrderBlocks {
    /// Pairs `(p₀ + k, q₀ + k)` for k in 0..m: contiguous position and velocity blocks.
    pub fn contiguous(p0: usize, q0: usize, m: usize) -> Self {
        Self {
            pairs: (0..m).map(|k| [p0 + k, q0 + k]).collect(),
        }
    }
}

/// Absolute tolerance: one value for every component, or one per component.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Atol {
    /// Same absolute tolerance for every component.
    Scalar(f64),
    /// One absolute tolerance per component.
    Vector(Vec<f64>),
}

impl Atol {
    /// The tolerance of component `i`.
    pub fn get(&self, i: usize) -> f64 {
        match self {
            Atol::Scalar(a) => *a,
            Atol::Vector(v) => v[i],
        }
    }
}

/// Error weights `wᵢ = 1 / (rtol |yᵢ| + atolᵢ)` as used by IDA's WRMS norm.
pub fn error_weights(y: &[f64], rtol: f64, atol: &Atol, w: &mut [f64]) {
    for (i, (wi, yi)) in w.iter_mut().zip(y).enumerate() {
        *wi = 1.0 / (rtol * yi.abs() + atol.get(i));
    }
}

/// Weighted root-mean-square norm `sqrt(Σ (vᵢ wᵢ)² / n)`.
pub fn wrms_norm(v: &[f64], w: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let s: f64 = v.iter().zip(w).map(|(a, b)| (a * b) * (a * b)).sum();
    (s / v.len() as f64).sqrt()
}

/// Integrator statistics after (part of) a run.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Accepted steps.
    pub steps: u64,
    /// Residual evaluations (including those for initial-condition calculation).
    pub residual_evals: u64,
    /// Jacobian evaluations.
    pub jacobian_evals: u64,
    /// Numerical LU factorizations.
    pub lu_factorizations: u64,
    /// Newton iterations.
    pub newton_iters: u64,
    /// Newton convergence failures.
    pub newton_failures: u64,
    /// Local error-test failures (IDA only; 0 for fixed-step BDF2).
    pub error_test_failures: u64,
    /// Krylov (GMRES) iterations, each a product `J v` and a preconditioner solve (IDA
    /// with `solver.krylov` only, else 0).
    #[serde(default)]
    pub linear_iters: u64,
    /// Krylov solves that did not reach their tolerance within their iterations: each
    /// counts as a Newton convergence failure, and IDA sets the preconditioner up again
    /// (IDA with `solver.krylov` only, else 0).
    #[serde(default)]
    pub linear_failures: u64,
    /// Evaluations of the root functions (with root functions only, else 0 and not
    /// written to the summary).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub root_evals: u64,
    /// Our nonlinear solver's failed attempts by kind and its Broyden updates
    /// (`solver.nonlinear`; not written when nothing was counted).
    #[serde(default, skip_serializing_if = "NewtonCounts::is_empty")]
    pub newton_detail: NewtonCounts,
    /// How far the solution has moved over the run: Σ over the steps of ‖yₙ − yₙ₋₁‖ in
    /// the weighted RMS norm of the integrator's weights 1/(rtol |y| + atol) (IDA's error
    /// weights, BDF2's Newton weights): tolerance units. The stall rule's measure of
    /// motion ([`crate::run`]). Not written to the summary.
    #[serde(skip)]
    pub path: f64,
    /// Order used on the last step.
    pub last_order: u32,
    /// Size of the last step.
    pub last_step: f64,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

/// Statistics of consecutive integrations (e.g. before and after a system change): counts
/// add up, the last order and step are those of the later one.
impl std::ops::AddAssign<&Stats> for Stats {
    fn add_assign(&mut self, b: &Stats) {
        self.steps += b.steps;
        self.residual_evals += b.residual_evals;
        self.jacobian_evals += b.jacobian_evals;
        self.lu_factorizations += b.lu_factorizations;
        self.newton_iters += b.newton_iters;
        self.newton_failures += b.newton_failures;
        self.error_test_failures += b.error_test_failures;
        self.linear_iters += b.linear_iters;
        self.linear_failures += b.linear_failures;
        self.root_evals += b.root_evals;
        self.newton_detail += &b.newton_detail;
        self.path += b.path;
        self.last_order = b.last_order;
        self.last_step = b.last_step;
    }
}

impl std::ops::Add<&Stats> for &Stats {
    type Output = Stats;
    fn add(self, b: &Stats) -> Stats {
        let mut s = self.clone();
        s += b;
        s
    }
}

/// Why an integration stopped before its target time.
#[derive(Debug, Clone, thiserror::Error)]
pub enum IntegratorError {
    /// A SUNDIALS function returned an error code.
    #[error("{function} failed at t = {t:.6e} with flag {flag} ({name}): {message}")]
    Sundials {
        /// The SUNDIALS function that failed.
        function: &'static str,
        /// Its return flag.
        flag: i32,
        /// The flag's name (IDAGetReturnFlagName).
        name: String,
        /// The last message from SUNDIALS' error handler.
        message: String,
        /// Integration time when it failed.
        t: f64,
    },
    /// The Newton iteration failed repeatedly (BDF2).
    #[error(
        "Newton iteration did not converge at t = {t:.6e} (step {step}, h = {h:.3e}): {reason}"
    )]
    NewtonFailed {
        /// Time at the start of the failing step.
        t: f64,
        /// Step number.
        step: u64,
        /// Step size.
        h: f64,
        /// What went wrong last.
        reason: String,
    },
    /// The step size fell below its minimum.
    #[error("step size fell below its minimum at t = {t:.6e} (h = {h:.3e}): {reason}")]
    StepTooSmall {
        /// Time.
        t: f64,
        /// Last step attempted.
        h: f64,
        /// The last failure.
        reason: String,
    },
    /// The linear solver failed (structurally singular matrix, a solver that does not fit
    /// the problem, ...), with what the integrator was doing.
    #[error("linear solver{}: {source}", context_prefix(context))]
    Linear {
        /// What the integrator was doing ("" when nothing more is known).
        context: &'static str,
        /// The solver's error.
        source: linsolve::LinearSolverError,
    },
    /// The problem reported a fatal error.
    #[error("problem error at t = {t:.6e}: {message}")]
    Problem {
        /// Time.
        t: f64,
        /// The message.
        message: String,
    },
    /// The driver asked to stop (e.g. Ctrl-C).
    #[error("interrupted at t = {t:.6e}")]
    Interrupted {
        /// Time of the last accepted step.
        t: f64,
    },
    /// Invalid options or input.
    #[error("invalid input: {0}")]
    Input(String),
}

fn context_prefix(context: &str) -> String {
    if context.is_empty() {
        String::new()
    } else {
        format!(" ({context})")
    }
}

impl IntegratorError {
    /// A linear-solver failure with no further context.
    pub fn linear(source: linsolve::LinearSolverError) -> Self {
        IntegratorError::Linear {
            context: "",
            source,
        }
    }
}

/// What every integrator sets up from a problem before its first step.
pub struct Setup {
    /// Initial time.
    pub t0: f64,
    /// Initial y, checked to have the problem's size.
    pub y0: Vec<f64>,
    /// Initial ẏ, likewise.
    pub yp0: Vec<f64>,
    /// The linear solver, its symbolic analysis of the Jacobian's pattern done.
    pub solver: Box<dyn LinearSolver>,
    /// Nonzeros of the pattern (length of the Jacobian's value array).
    pub nnz: usize,
    /// The problem's breakpoints after t0, sorted, without repeats.
    pub breakpoints: Vec<f64>,
}

impl Setup {
    /// Checks the initial values and the per-component tolerances against the problem's
    /// size, builds the factory's linear solver and analyses the pattern.
    pub fn new<D: Dae>(
        dae: &D,
        factory: &dyn LinearSolverFactory,
        atol: &Atol,
    ) -> Result<Self, IntegratorError> {
        let n = dae.size();
        let (t0, y0, yp0) = dae.initial();
        if y0.len() != n || yp0.len() != n {
            return Err(IntegratorError::Input(format!(
                "initial values have lengths {} and {}, the system has {n} unknowns",
                y0.len(),
                yp0.len()
            )));
        }
        if let Atol::Vector(v) = atol {
            if v.len() != n {
                return Err(IntegratorError::Input(format!(
                    "{} absolute tolerances for {n} unknowns",
                    v.len()
                )));
            }
        }
        let linear = IntegratorError::linear;
        let mut solver = factory.build_for(dae).map_err(linear)?;
        solver.analyse(dae.pattern()).map_err(linear)?;
        let mut breakpoints: Vec<f64> = dae.breakpoints().into_iter().filter(|b| *b > t0).collect();
        breakpoints.sort_by(f64::total_cmp);
        breakpoints.dedup();
        Ok(Self {
            t0,
            y0,
            yp0,
            solver,
            nnz: dae.pattern().compute_nnz(),
            breakpoints,
        })
    }
}

/// What every integrator offers to a driver: advance to a time, look at the state.
pub trait Integrator {
    /// Advances the solution to `tout` (never past the next breakpoint without stopping
    /// there) and returns the state at `tout`. `on_step` is called after every internal
    /// step with (t, stats) so a driver can show progress; returning `false` stops the
    /// integration with [`IntegratorError::Interrupted`].
    /// Output times only move forward from the current one (NaN is refused as well).
    fn advance_to(
        &mut self,
        tout: f64,
        on_step: &mut dyn FnMut(f64, &Stats) -> bool,
    ) -> Result<(), IntegratorError> {
        if tout >= self.t() {
            self.advance(tout, on_step)
        } else {
            Err(IntegratorError::Input(format!(
                "output time {tout} is before the current time {}",
                self.t()
            )))
        }
    }
    /// [`Integrator::advance_to`] for a `tout` at or after the current output time.
    fn advance(
        &mut self,
        tout: f64,
        on_step: &mut dyn FnMut(f64, &Stats) -> bool,
    ) -> Result<(), IntegratorError>;
    /// Current output time (the last `tout` reached).
    fn t(&self) -> f64;
    /// y at the current output time.
    fn y(&self) -> &[f64];
    /// ẏ at the current output time.
    fn yp(&self) -> &[f64];
    /// The last accepted step: its time, y and ẏ (at or past the current output time;
    /// where a run that stops between output times got to).
    fn last_step(&self) -> (f64, &[f64], &[f64]);
    /// Statistics so far.
    fn stats(&self) -> Stats;
    /// The root of the DAE's root functions the last [`Integrator::advance_to`] stopped at:
    /// with root functions ([`Dae::root_directions`]) an advance stops at the first zero
    /// before its output time, and then [`Integrator::t`], `y` and `yp` are the root's
    /// time and state; the next advance goes on from there. `None` when it reached its
    /// output time.
    fn root(&self) -> Option<&Root> {
        None
    }
}

/// Consistent initial values for a restart: solves F(t, y, ẏ) = 0 by Newton's method for
/// y in the components where `solve_for_y` is true and for ẏ in the others (the scheme of
/// IDACalcIC, with the split chosen by the caller instead of by the id vector). The
/// iteration matrix has columns ∂F/∂y (J at cj = 0) for the first kind and ∂F/∂ẏ
/// (J at cj = 1 minus J at cj = 0) for the second.
///
/// Used when a system is restarted from a state that satisfies a different system: with
/// inertia switched off while the cell still moves, its rigid vertical mode becomes
/// algebraic and must jump to equilibrium (solve for u with u̇ = v given), while the μ_as
/// ODEs keep μ_as and get a consistent μ̇_as. Converged when the weighted RMS norm of the
/// update is below 1e-3 (weights from `rtol`, `atol`); returns the iterations taken.
#[allow(clippy::too_many_arguments)]
pub fn consistent_init(
    dae: &mut dyn Dae,
    t: f64,
    y: &mut [f64],
    yp: &mut [f64],
    solve_for_y: &[bool],
    factory: &dyn LinearSolverFactory,
    rtol: f64,
    atol: &Atol,
) -> Result<u32, IntegratorError> {
    const MAX_ITERS: u32 = 30;
    let n = dae.size();
    let pattern = dae.pattern().clone();
    let mut solver = factory.build_for(&*dae).map_err(IntegratorError::linear)?;
    solver.analyse(&pattern).map_err(IntegratorError::linear)?;
    let nnz = pattern.compute_nnz();
    let (mut j0, mut j1) = (vec![0.0; nnz], vec![0.0; nnz]);
    let (mut r, mut w) = (vec![0.0; n], vec![0.0; n]);
    error_weights(y, rtol, atol, &mut w);
    let problem = |e: DaeError| IntegratorError::Problem {
        t,
        message: format!("consistent initial values: {e}"),
    };
    let linear = |e: linsolve::LinearSolverError| IntegratorError::Linear {
        context: "consistent initial values",
        source: e,
    };
    for it in 1..=MAX_ITERS {
        dae.residual(State::new(t, y, yp), &mut r)
            .map_err(problem)?;
        dae.jacobian(State::new(t, y, yp), 0.0, &mut j0)
            .map_err(problem)?;
        dae.jacobian(State::new(t, y, yp), 1.0, &mut j1)
            .map_err(problem)?;
        for (c, &for_y) in solve_for_y.iter().enumerate() {
            if !for_y {
                for k in pattern.col_ptr()[c]..pattern.col_ptr()[c + 1] {
                    j0[k] = j1[k] - j0[k];
                }
            }
        }
        solver.factorize(&j0).map_err(linear)?;
        for v in r.iter_mut() {
            *v = -*v;
        }
        solver.solve_in_place(&mut r).map_err(linear)?;
        for (i, d) in r.iter().enumerate() {
            if solve_for_y[i] {
                y[i] += d;
            } else {
                yp[i] += d;
            }
        }
        if wrms_norm(&r, &w) <= 1e-3 {
            return Ok(it);
        }
    }
    Err(IntegratorError::NewtonFailed {
        t,
        step: 0,
        h: 0.0,
        reason: format!(
            "consistent initial values: no convergence in {MAX_ITERS} Newton iterations"
        ),
    })
}
