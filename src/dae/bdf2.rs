//! Fixed-step BDF2 on the [`Dae`] trait: the reference that verifies IDA.
//!
//! **Formula.** With steps hₙ (this one) and hₙ₋₁ (the previous), ω = hₙ/hₙ₋₁, the
//! variable-coefficient BDF2 derivative is
//!
//! ẏₙ₊₁ = [ (1+2ω)/(1+ω) yₙ₊₁ − (1+ω) yₙ + ω²/(1+ω) yₙ₋₁ ] / hₙ,
//!
//! i.e. ẏₙ₊₁ = cj yₙ₊₁ + β with cj = (1+2ω)/((1+ω)hₙ). With a fixed step ω = 1 and this is
//! the classical (3yₙ₊₁ − 4yₙ + yₙ₋₁)/(2h). ω ≠ 1 only where the step must land on a
//! breakpoint (each segment between breakpoints is split into equal steps no longer than
//! `dt`) or after a step cut.
//!
//! **Start.** The first step is backward Euler (BDF1). Its local error is O(h²), one step
//! only, so the global error stays O(h²): the method is second order (tested on a
//! closed-form DAE). It is `start_fraction` of dt, and the steps after it grow by at most
//! `max_growth` each until they reach the planned step, so the start scales with dt: a
//! first step cut to a size of its own (a Newton failure at the full dt) would otherwise
//! begin every rung of a dt ladder in the same state, and the error of the start would
//! not fall with dt.
//!
//! **Newton.** Modified Newton on F(t, y, cj y + β) = 0 with the iteration matrix
//! J = ∂F/∂y + cj ∂F/∂ẏ factorized once and reused across iterations and steps while cj
//! is unchanged. Convergence is tested on the update, weighted like IDA's:
//! ‖δ‖ = WRMS(δ, w), wᵢ = 1/(rtol |yᵢ| + atolᵢ). With δ₀ the first update and
//! ρ = (‖δₘ‖/‖δ₀‖)^{1/m} the rate, the iteration has converged when ‖δ₀‖ ≤ 10⁻⁴·tol or
//! ρ/(1−ρ)·‖δₘ‖ ≤ tol (tol = `newton_tol`, default 0.33 as in IDA); it fails when ρ > 0.9
//! or after `max_newton_iters`. A failure with a stale Jacobian re-evaluates it and retries;
//! a failure with a fresh one retries with full Newton (the Jacobian re-evaluated at every
//! iterate, for nonlinearities such as contact onset within one step); a failure of that
//! (or an inadmissible state) halves the step, at most `max_cuts` times in a row, then
//! stops with an error naming the time, step and reason.
//!
//! **Output.** Values between steps come from the cubic Hermite interpolant of
//! (yₙ, ẏₙ, yₙ₊₁, ẏₙ₊₁), which is more accurate than the method, so outputs keep order 2.

use super::linsolve::{FaerFactory, LinearSolver, LinearSolverError, SharedFactory};
use super::{
    Atol, Dae, DaeError, Integrator, IntegratorError, Root, Setup, State, Stats, crosses,
    error_weights, wrms_norm,
};

/// BDF2 settings.
#[derive(Debug, Clone)]
pub struct Bdf2Options {
    /// Nominal step size.
    pub dt: f64,
    /// Relative tolerance of the Newton weights.
    pub rtol: f64,
    /// Absolute tolerance(s) of the Newton weights.
    pub atol: Atol,
    /// Newton convergence threshold on the weighted update (IDA uses 0.33).
    pub newton_tol: f64,
    /// Most Newton iterations per attempt.
    pub max_newton_iters: u32,
    /// Most consecutive step halvings before giving up.
    pub max_cuts: u32,
    /// The first step after a (re)start as a fraction of dt (module docs, "Start").
    pub start_fraction: f64,
    /// Largest ratio of a step to the one before it while the steps grow from the start.
    pub max_growth: f64,
    /// The stored factorization is reused while cj agrees with its own to this relative
    /// difference (0: bit for bit).
    pub cj_reuse_tol: f64,
    /// Which sparse LU factorizes the iteration matrix.
    pub linear_solver: SharedFactory,
}

impl Default for Bdf2Options {
    fn default() -> Self {
        Self {
            dt: 1.0,
            rtol: 1e-6,
            atol: Atol::Scalar(1e-8),
            newton_tol: 0.33,
            max_newton_iters: 4,
            max_cuts: 10,
            start_fraction: 0.25,
            max_growth: 1.5,
            cj_reuse_tol: 1e-9,
            linear_solver: std::sync::Arc::new(FaerFactory),
        }
    }
}

/// Fixed-step BDF2 integrating a [`Dae`].
pub struct Bdf2<D: Dae> {
    dae: D,
    opts: Bdf2Options,
    solver: Box<dyn LinearSolver>,
    values: Vec<f64>,
    /// cj of the current factorization (None: no valid factorization).
    factor_cj: Option<f64>,
    breakpoints: Vec<f64>,
    // Last two accepted points: (t_prev, y_prev, yp_prev) and (tn, yn, ypn).
    tn: f64,
    yn: Vec<f64>,
    ypn: Vec<f64>,
    t_prev: f64,
    y_prev: Vec<f64>,
    yp_prev: Vec<f64>,
    /// Previous step size (None before the first step: use BDF1).
    h_prev: Option<f64>,
    /// Whether the steps are still growing from the start (module docs, "Start").
    ramping: bool,
    /// Output point.
    t_out: f64,
    y_out: Vec<f64>,
    yp_out: Vec<f64>,
    stats: Stats,
    /// Step cuts taken so far (not part of IDA's statistics).
    pub cuts: u64,
    /// The root functions' directions ([`Dae::root_directions`]) and their values at the
    /// last accepted step.
    root_dirs: Vec<i32>,
    g_n: Vec<f64>,
    /// The root the last advance stopped at, and one found past its output time, to be
    /// reported by the next.
    root: Option<Root>,
    pending_root: Option<Root>,
    // Work vectors.
    y_new: Vec<f64>,
    beta: Vec<f64>,
    r: Vec<f64>,
    w: Vec<f64>,
}

/// Why one step attempt failed.
enum StepFailure {
    Newton(String),
    Fatal(IntegratorError),
}

impl<D: Dae> Bdf2<D> {
    /// Sets BDF2 up on `dae` from its consistent initial values.
    pub fn new(dae: D, opts: Bdf2Options) -> Result<Self, IntegratorError> {
        if !(opts.dt > 0.0) || !(opts.newton_tol > 0.0) || opts.max_newton_iters == 0 {
            return Err(IntegratorError::Input(format!(
                "BDF2 needs dt > 0, newton_tol > 0 and max_newton_iters ≥ 1 (got {}, {}, {})",
                opts.dt, opts.newton_tol, opts.max_newton_iters
            )));
        }
        let n = dae.size();
        let setup = Setup::new(&dae, opts.linear_solver.as_ref(), &opts.atol)?;
        let (t0, y0, yp0) = (setup.t0, setup.y0, setup.yp0);
        let mut dae = dae;
        let root_dirs = dae.root_directions();
        let mut g_n = vec![0.0; root_dirs.len()];
        if !root_dirs.is_empty() {
            root_values(&mut dae, t0, &y0, &yp0, &mut g_n)?;
        }
        Ok(Self {
            dae,
            opts,
            solver: setup.solver,
            values: vec![0.0; setup.nnz],
            factor_cj: None,
            breakpoints: setup.breakpoints,
            tn: t0,
            yn: y0.clone(),
            ypn: yp0.clone(),
            t_prev: t0,
            y_prev: y0.clone(),
            yp_prev: yp0.clone(),
            h_prev: None,
            ramping: true,
            t_out: t0,
            y_out: y0,
            yp_out: yp0,
            stats: Stats {
                root_evals: u64::from(!g_n.is_empty()),
                ..Stats::default()
            },
            cuts: 0,
            root_dirs,
            g_n,
            root: None,
            pending_root: None,
            y_new: vec![0.0; n],
            beta: vec![0.0; n],
            r: vec![0.0; n],
            w: vec![0.0; n],
        })
    }

    /// The problem being integrated.
    pub fn dae(&self) -> &D {
        &self.dae
    }

    /// Mutable access to the problem.
    pub fn dae_mut(&mut self) -> &mut D {
        &mut self.dae
    }

    /// Time of the last accepted step.
    pub fn t_internal(&self) -> f64 {
        self.tn
    }

    /// The nominal step for the segment ending at the next breakpoint (or `limit`): equal
    /// steps no longer than dt that land exactly on it.
    fn planned_step(&self) -> f64 {
        let eps = 8.0 * f64::EPSILON * self.tn.abs().max(1.0);
        let end = self
            .breakpoints
            .iter()
            .copied()
            .find(|&b| b > self.tn + eps);
        match end {
            Some(b) => {
                let remaining = b - self.tn;
                let k = (remaining / self.opts.dt * (1.0 - 1e-12)).ceil().max(1.0);
                remaining / k
            }
            None => self.opts.dt,
        }
    }

    /// One attempt at a step of size h; on success the history is shifted.
    fn try_step(&mut self, h: f64) -> Result<(), StepFailure> {
        let n = self.yn.len();
        let t_new = self.tn + h;
        // BDF coefficients: ẏ_new = cj y_new + β.
        let cj;
        match self.h_prev {
            None => {
                cj = 1.0 / h;
                for i in 0..n {
                    self.beta[i] = -self.yn[i] / h;
                }
            }
            Some(hp) => {
                let om = h / hp;
                cj = (1.0 + 2.0 * om) / ((1.0 + om) * h);
                let a1 = -(1.0 + om) / h;
                let a2 = om * om / ((1.0 + om) * h);
                for i in 0..n {
                    self.beta[i] = a1 * self.yn[i] + a2 * self.y_prev[i];
                }
            }
        }
        error_weights(&self.yn, self.opts.rtol, &self.opts.atol, &mut self.w);
        // Attempts: (0) modified Newton with the stored factorization, if its cj matches;
        // (1) modified Newton with a fresh Jacobian at the predictor; (2) full Newton, the
        // Jacobian re-evaluated at every iterate (contact onset changes the stiffness within
        // one step). All failing fails the step. "Matches" is to `cj_reuse_tol`: the equal
        // steps of a segment are recomputed at every step (remaining / k) and differ in their
        // last bits, and so would cj.
        let stale_ok = self
            .factor_cj
            .is_some_and(|c| (c - cj).abs() <= self.opts.cj_reuse_tol * cj.abs());
        let mut last = String::new();
        for attempt in 0..3 {
            if attempt == 0 && !stale_ok {
                continue;
            }
            // Predictor: y_new = y + h ẏ (y itself on the first step: after a restart ẏ
            // may hold velocities of the algebraic components the new system does not
            // constrain, e.g. a rigid mode that just became algebraic).
            let lead = if self.h_prev.is_some() { h } else { 0.0 };
            for i in 0..n {
                self.y_new[i] = self.yn[i] + lead * self.ypn[i];
            }
            if attempt >= 1 {
                self.refresh_jacobian(t_new, cj)?;
            }
            match self.newton(t_new, cj, attempt == 2) {
                Ok(()) => {
                    // Accept: shift history.
                    std::mem::swap(&mut self.y_prev, &mut self.yn);
                    std::mem::swap(&mut self.yp_prev, &mut self.ypn);
                    self.t_prev = self.tn;
                    self.yn.copy_from_slice(&self.y_new);
                    for i in 0..n {
                        self.ypn[i] = cj * self.yn[i] + self.beta[i];
                    }
                    self.tn = t_new;
                    self.h_prev = Some(h);
                    // The step's length in the Newton weights ([`Stats::path`]); y_new is
                    // free until the next predictor.
                    for i in 0..n {
                        self.y_new[i] = self.yn[i] - self.y_prev[i];
                    }
                    self.stats.path += wrms_norm(&self.y_new, &self.w);
                    self.stats.steps += 1;
                    self.stats.last_step = h;
                    self.stats.last_order = if self.stats.steps == 1 { 1 } else { 2 };
                    return Ok(());
                }
                Err(StepFailure::Newton(m)) => {
                    self.stats.newton_failures += 1;
                    last = m;
                }
                Err(e) => return Err(e),
            }
        }
        Err(StepFailure::Newton(last))
    }

    /// Evaluates J at the predicted point and factorizes it.
    fn refresh_jacobian(&mut self, t_new: f64, cj: f64) -> Result<(), StepFailure> {
        self.factor_cj = None;
        let n = self.yn.len();
        let yp_pred: Vec<f64> = (0..n).map(|i| cj * self.y_new[i] + self.beta[i]).collect();
        self.stats.jacobian_evals += 1;
        match self.dae.jacobian(
            State::new(t_new, &self.y_new, &yp_pred),
            cj,
            &mut self.values,
        ) {
            Ok(()) => {}
            Err(DaeError::Inadmissible(why)) => {
                return Err(StepFailure::Newton(format!(
                    "Jacobian: inadmissible state: {why}"
                )));
            }
            Err(DaeError::Fatal(m)) => {
                return Err(StepFailure::Fatal(IntegratorError::Problem {
                    t: t_new,
                    message: m,
                }));
            }
        }
        match self.solver.factorize(&self.values) {
            Ok(()) => {
                self.stats.lu_factorizations += 1;
                self.factor_cj = Some(cj);
                Ok(())
            }
            Err(e @ LinearSolverError::Singular { .. }) => Err(StepFailure::Newton(e.to_string())),
            Err(e) => Err(StepFailure::Fatal(IntegratorError::linear(e))),
        }
    }

    /// Modified Newton from the predictor in `y_new`.
    /// Newton from the predictor in `y_new`: modified (the stored factorization) or, with
    /// `full`, re-evaluating the Jacobian at every iterate after the first.
    fn newton(&mut self, t_new: f64, cj: f64, full: bool) -> Result<(), StepFailure> {
        let n = self.yn.len();
        let mut yp_new = vec![0.0; n];
        let mut norm0 = 0.0;
        let tol = self.opts.newton_tol;
        let iters = if full {
            2 * self.opts.max_newton_iters
        } else {
            self.opts.max_newton_iters
        };
        for m in 0..iters {
            if full && m > 0 {
                self.refresh_jacobian(t_new, cj)?;
            }
            for i in 0..n {
                yp_new[i] = cj * self.y_new[i] + self.beta[i];
            }
            self.stats.residual_evals += 1;
            match self
                .dae
                .residual(State::new(t_new, &self.y_new, &yp_new), &mut self.r)
            {
                Ok(()) => {}
                Err(DaeError::Inadmissible(why)) => {
                    return Err(StepFailure::Newton(format!("inadmissible state: {why}")));
                }
                Err(DaeError::Fatal(msg)) => {
                    return Err(StepFailure::Fatal(IntegratorError::Problem {
                        t: t_new,
                        message: msg,
                    }));
                }
            }
            if self.r.iter().any(|v| !v.is_finite()) {
                return Err(StepFailure::Newton("non-finite residual".into()));
            }
            for v in self.r.iter_mut() {
                *v = -*v;
            }
            match self.solver.solve_in_place(&mut self.r) {
                Ok(()) => {}
                Err(e @ LinearSolverError::Singular { .. }) => {
                    return Err(StepFailure::Newton(e.to_string()));
                }
                Err(e) => return Err(StepFailure::Fatal(IntegratorError::linear(e))),
            }
            self.stats.newton_iters += 1;
            for i in 0..n {
                self.y_new[i] += self.r[i];
            }
            let norm = wrms_norm(&self.r, &self.w);
            if m == 0 {
                norm0 = norm;
                if norm <= 1e-4 * tol {
                    return Ok(());
                }
            } else {
                let rate = (norm / norm0).powf(1.0 / m as f64);
                if rate > 0.9 {
                    return Err(StepFailure::Newton(format!(
                        "Newton diverging (rate {rate:.2}, update norm {norm:.2e})"
                    )));
                }
                if rate / (1.0 - rate) * norm <= tol {
                    return Ok(());
                }
            }
        }
        Err(StepFailure::Newton(format!(
            "no convergence in {iters} Newton iterations"
        )))
    }

    /// After an accepted step: the first zero of the root functions in it, located on the
    /// step's cubic Hermite interpolant ([`Self::interpolate`]) by the Illinois method to
    /// IDA's tolerance, 100 ε max(|t|, |h|) (the step's accuracy: the interpolant is the
    /// solution to O(h⁴) locally). Leaves `y_out`, `yp_out` at the root when there is one.
    fn locate_root(&mut self) -> Result<Option<Root>, IntegratorError> {
        if self.root_dirs.is_empty() {
            return Ok(None);
        }
        let mut g1 = vec![0.0; self.root_dirs.len()];
        root_values(&mut self.dae, self.tn, &self.yn, &self.ypn, &mut g1)?;
        self.stats.root_evals += 1;
        let g0 = std::mem::replace(&mut self.g_n, g1.clone());
        let crossing: Vec<usize> = (0..g1.len())
            .filter(|&i| crosses(g0[i], g1[i], self.root_dirs[i]))
            .collect();
        if crossing.is_empty() {
            return Ok(None);
        }
        let h = self.tn - self.t_prev;
        let tol = 100.0 * f64::EPSILON * self.tn.abs().max(h.abs());
        let mut g = vec![0.0; g1.len()];
        // The earliest zero over the functions that cross, each by Illinois on [t_prev, tn].
        let mut first = (self.tn, Vec::new());
        for &i in &crossing {
            let (mut a, mut b, mut ga, mut gb) = (self.t_prev, self.tn, g0[i], g1[i]);
            let mut side = 0;
            while b - a > tol {
                let mut m = b - gb * (b - a) / (gb - ga);
                if !(m > a && m < b) {
                    m = 0.5 * (a + b);
                }
                self.interpolate(m);
                root_values(&mut self.dae, m, &self.y_out, &self.yp_out, &mut g)?;
                self.stats.root_evals += 1;
                let gm = g[i];
                if gm == 0.0 {
                    (a, b) = (m, m);
                } else if (gm < 0.0) == (gb < 0.0) {
                    (b, gb) = (m, gm);
                    if side == -1 {
                        ga *= 0.5;
                    }
                    side = -1;
                } else {
                    (a, ga) = (m, gm);
                    if side == 1 {
                        gb *= 0.5;
                    }
                    side = 1;
                }
            }
            if b < first.0 - tol {
                first = (b, vec![i]);
            } else if (b - first.0).abs() <= tol {
                first.1.push(i);
            }
        }
        let (t, functions) = first;
        self.interpolate(t);
        let mut crossings = vec![0; g1.len()];
        for i in functions {
            crossings[i] = if g1[i] > g0[i] { 1 } else { -1 };
        }
        Ok(Some(Root::new(t, crossings)))
    }

    /// Cubic Hermite interpolation of the last step at time `t`.
    fn interpolate(&mut self, t: f64) {
        let h = self.tn - self.t_prev;
        if h <= 0.0 {
            self.y_out.copy_from_slice(&self.yn);
            self.yp_out.copy_from_slice(&self.ypn);
            return;
        }
        let s = (t - self.t_prev) / h;
        let (h00, h10, h01, h11) = (
            2.0 * s.powi(3) - 3.0 * s * s + 1.0,
            s.powi(3) - 2.0 * s * s + s,
            -2.0 * s.powi(3) + 3.0 * s * s,
            s.powi(3) - s * s,
        );
        let (d00, d10, d01, d11) = (
            6.0 * s * s - 6.0 * s,
            3.0 * s * s - 4.0 * s + 1.0,
            -6.0 * s * s + 6.0 * s,
            3.0 * s * s - 2.0 * s,
        );
        for i in 0..self.yn.len() {
            let (y0, y1, p0, p1) = (self.y_prev[i], self.yn[i], self.yp_prev[i], self.ypn[i]);
            self.y_out[i] = h00 * y0 + h10 * h * p0 + h01 * y1 + h11 * h * p1;
            self.yp_out[i] = (d00 * y0 + d01 * y1) / h + d10 * p0 + d11 * p1;
        }
    }
}

impl<D: Dae> Integrator for Bdf2<D> {
    fn t(&self) -> f64 {
        self.t_out
    }

    fn advance(
        &mut self,
        tout: f64,
        on_step: &mut dyn FnMut(f64, &Stats) -> bool,
    ) -> Result<(), IntegratorError> {
        let eps = 8.0 * f64::EPSILON * tout.abs().max(1.0);
        self.root = None;
        if let Some(r) = self.pending_root.take() {
            // A root found past the last output time, in the last step.
            if r.t <= tout + eps {
                self.interpolate(r.t);
                self.t_out = r.t;
                self.root = Some(r);
                return Ok(());
            }
            self.pending_root = Some(r);
        }
        while self.tn < tout - eps && self.pending_root.is_none() {
            let planned = self.planned_step();
            let mut h = match (self.ramping, self.h_prev) {
                (false, _) => planned,
                (true, None) => planned.min(self.opts.start_fraction * self.opts.dt),
                (true, Some(hp)) => planned.min(self.opts.max_growth * hp),
            };
            self.ramping = h < planned;
            let mut cuts = 0;
            loop {
                match self.try_step(h) {
                    Ok(()) => break,
                    Err(StepFailure::Fatal(e)) => return Err(e),
                    Err(StepFailure::Newton(reason)) => {
                        cuts += 1;
                        self.cuts += 1;
                        if cuts > self.opts.max_cuts {
                            return Err(IntegratorError::NewtonFailed {
                                t: self.tn,
                                step: self.stats.steps + 1,
                                h,
                                reason: format!(
                                    "{reason} (after {} step halvings)",
                                    self.opts.max_cuts
                                ),
                            });
                        }
                        h *= 0.5;
                    }
                }
            }
            self.dae.accepted_step(self.tn, &self.yn, &self.ypn);
            // A root in the step is reported first, as IDA does (a driver that stops after
            // every step still sees it).
            if let Some(r) = self.locate_root()? {
                if r.t <= tout + eps {
                    self.t_out = r.t;
                    self.root = Some(r);
                    return Ok(());
                }
                self.pending_root = Some(r);
            }
            let stats = self.stats.clone();
            if !on_step(self.tn, &stats) {
                return Err(IntegratorError::Interrupted { t: self.tn });
            }
        }
        if (self.tn - tout).abs() <= eps {
            self.y_out.copy_from_slice(&self.yn);
            self.yp_out.copy_from_slice(&self.ypn);
        } else {
            self.interpolate(tout);
        }
        self.t_out = tout;
        Ok(())
    }

    fn y(&self) -> &[f64] {
        &self.y_out
    }

    fn yp(&self) -> &[f64] {
        &self.yp_out
    }

    fn last_step(&self) -> (f64, &[f64], &[f64]) {
        (self.tn, &self.yn, &self.ypn)
    }

    fn stats(&self) -> Stats {
        self.stats.clone()
    }

    fn root(&self) -> Option<&Root> {
        self.root.as_ref()
    }
}

/// The DAE's root functions at (t, y, ẏ) into `g`.
fn root_values<D: Dae>(
    dae: &mut D,
    t: f64,
    y: &[f64],
    yp: &[f64],
    g: &mut [f64],
) -> Result<(), IntegratorError> {
    dae.root_functions(State::new(t, y, yp), g)
        .map_err(|e| IntegratorError::Problem {
            t,
            message: format!("root functions: {e}"),
        })
}
