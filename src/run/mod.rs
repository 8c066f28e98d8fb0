//! `cellsim run`: one scene from its case file to its outputs, written as the run goes.
//!
//! The driver reads as the algorithm: make the mesh → build the model → set up the
//! integrator → loop over output times { advance; observe; write a CSV row and, at phase
//! ends, the state } → write the summary. Every output is flushed when written, so a
//! failure or an interruption keeps everything computed so far, and the summary is
//! written in every case (with the reason, time and step when the run did not finish).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use crate::case::{self, Case, InertiaMode};
use crate::dae::bdf2::{Bdf2, Bdf2Options};
use crate::dae::{Atol, Dae, Integrator, IntegratorError, Stats};
use crate::fem::{Domain, Mesh, MeshError};
use crate::model::{
    CellModel, CellOf, HalfPlane, ModelError, ModelParams, Quarter, Restart, Shape, State,
};
use crate::render::{QuarterSnapshotWriter, SnapshotOptions, SnapshotWriter};
use crate::run_files::Observables;
use crate::run_files::read::STOPPED;
use crate::run_files::{
    self, Failure, FailureKind, MeshFile, SettingsUsed, Snapshot, StateFile, StopPlace, Summary,
    TimeBreakdown, Unknowns,
};
use crate::scene::{self, SceneError};
use crate::solver::{self, Limits, Settings};
use crate::stop::{StopFlag, signal_name};
use crate::sundials::{Ida, IdaOptions, Krylov};

mod cell;
mod events;
pub mod sensitivity;
mod shared;
use cell::{Cell, ModelView, RunModel};
pub use shared::{Member, run_all, shared_until};

/// How a run reports progress.
#[derive(Clone, Default)]
pub enum Progress {
    /// Nothing (`--quiet`).
    #[default]
    Hidden,
    /// A progress line redrawn in place (stderr is a terminal).
    Bar(ProgressBar),
    /// A plain line on stderr after the first step and then every `every` of wall time
    /// (stderr is a file or a pipe, as in a batch job's log): simulated time, steps and
    /// wall time, prefixed by `label`.
    Lines {
        /// Prefix of each line (the case name).
        label: String,
        /// Interval between lines.
        every: Duration,
    },
}

/// Interval between plain progress lines when stderr is not a terminal.
pub const PROGRESS_LINE_INTERVAL: Duration = Duration::from_secs(10);

impl Progress {
    /// A bar on a terminal, plain lines every [`PROGRESS_LINE_INTERVAL`] otherwise,
    /// nothing when `quiet`.
    pub fn for_stderr(case: &Case, quiet: bool) -> Self {
        use std::io::IsTerminal;
        if quiet {
            Progress::Hidden
        } else if std::io::stderr().is_terminal() {
            Progress::Bar(progress_bar(case, true))
        } else {
            Progress::Lines {
                label: case.name.clone(),
                every: PROGRESS_LINE_INTERVAL,
            }
        }
    }
}

/// Shows a run's progress after each step, as its [`Progress`] asks.
struct Reporter {
    progress: Progress,
    t_end: f64,
    start: Instant,
    /// When the last plain line was written (`None`: none yet; the first step writes one).
    last_line: Option<Instant>,
}

impl Reporter {
    fn new(progress: &Progress, t_end: f64) -> Self {
        let now = Instant::now();
        Self {
            progress: progress.clone(),
            t_end,
            start: now,
            last_line: None,
        }
    }

    fn step(&mut self, t: f64, s: &Stats) {
        match &self.progress {
            Progress::Hidden => {}
            Progress::Bar(bar) => {
                bar.set_position((t * 1000.0).round().max(0.0) as u64);
                bar.set_message(format!(
                    "t = {t:>9.3e} s  step {:>6}  order {}  h = {:.2e}",
                    s.steps, s.last_order, s.last_step
                ));
            }
            Progress::Lines { label, every } => {
                if self.last_line.is_none_or(|l| l.elapsed() >= *every) {
                    self.last_line = Some(Instant::now());
                    use std::io::Write;
                    // A closed stderr must not stop the run.
                    let _ = writeln!(
                        std::io::stderr(),
                        "{label}: t = {t:.4e} s of {:.4e} s ({:.1} %), {} steps, h = {:.2e} s, wall {:.1} s",
                        self.t_end,
                        100.0 * t / self.t_end,
                        s.steps,
                        s.last_step,
                        self.start.elapsed().as_secs_f64()
                    );
                }
            }
        }
    }

    /// The run's end moved to `t_end` (a phase started on its condition).
    fn set_end(&mut self, t_end: f64) {
        self.t_end = t_end;
        if let Progress::Bar(bar) = &self.progress {
            bar.set_length((t_end * 1000.0).round().max(1.0) as u64);
        }
    }

    fn finish(&self) {
        if let Progress::Bar(bar) = &self.progress {
            bar.finish_and_clear();
        }
    }
}

/// Steps in the stall rule's sliding window (see `StepGuard`).
pub const STALL_STEPS: usize = 1000;
/// Stall threshold on the mean step over the window, as a fraction of the regular output
/// interval t_end / n_times.
pub const STALL_FRACTION: f64 = 1e-4;
/// Largest motion of the solution over the stall rule's window, in tolerance units
/// ([`Stats::path`]), for its short steps to count as a stall: one unit a step on average.
/// IDA sizes its steps for a local error of about one unit; steps that are short and move
/// the solution by less than that are held back by something else (Newton failures), while
/// a fast motion the model really makes (a snap-through, the ringing of a landing with
/// inertia) moves it by more: 1.0e4 units over the window in the snap of the J f_as
/// push-pull at t ≈ 47 225 s, 1.2e6 in a ringing landing.
pub const STALL_PATH: f64 = STALL_STEPS as f64;

/// Why the driver stopped the integrator before its output time (not a failure of the
/// method itself).
#[derive(Debug, Clone, PartialEq)]
pub enum StopCause {
    /// A signal asked to stop (SIGINT, SIGTERM, SIGHUP).
    Signal(i32),
    /// The wall-clock budget was spent \[s\].
    Budget(f64),
    /// More than `max_steps` steps between two output times.
    StepLimit {
        /// The limit (`solver.max_steps`).
        max_steps: u64,
        /// The output time being worked towards \[s\].
        tout: f64,
    },
    /// The mean step over the last [`STALL_STEPS`] steps fell below the stall threshold.
    Stalled {
        /// The threshold \[s\].
        threshold: f64,
        /// Simulated time covered by those steps \[s\].
        advanced: f64,
        /// Step size \[s\] and order of the last step.
        h: f64,
        /// BDF order of the last step.
        order: u32,
        /// Error-test and Newton convergence failures during those steps.
        error_test_failures: u64,
        /// Newton convergence failures during those steps.
        newton_failures: u64,
        /// How far the solution moved during those steps, in tolerance units.
        path: f64,
    },
}

impl StopCause {
    /// The reason written in the summary, for a stop at time `t`.
    pub fn reason(&self, t: f64) -> String {
        match self {
            StopCause::Signal(s) => format!("interrupted by {} at t = {t:.6e} s", signal_name(*s)),
            StopCause::Budget(limit) => {
                format!("wall-clock budget of {limit} s exhausted at t = {t:.6e} s")
            }
            StopCause::StepLimit { max_steps, tout } => format!(
                "step limit: more than solver.max_steps = {max_steps} steps between two output \
                 times, at t = {t:.6e} s (next output at {tout:.6e} s)"
            ),
            StopCause::Stalled {
                threshold,
                advanced,
                h,
                order,
                error_test_failures,
                newton_failures,
                path,
            } => {
                let kind = if error_test_failures + newton_failures == 0 {
                    "none (the steps were accepted at that size)".to_string()
                } else if error_test_failures >= newton_failures {
                    format!(
                        "local error test ({error_test_failures} error-test and \
                         {newton_failures} Newton convergence failures)"
                    )
                } else {
                    format!(
                        "Newton convergence ({newton_failures} convergence and \
                         {error_test_failures} error-test failures)"
                    )
                };
                format!(
                    "stalled at t = {t:.6e} s: the last {STALL_STEPS} steps advanced {advanced:.3e} s, \
                     a mean step below {threshold:.3e} s ({STALL_FRACTION:e} of the output \
                     interval), and moved the solution by {path:.3e} tolerance units; last step h = {h:.3e} s, order {order}; failures in those \
                     steps: {kind}. Tighter tolerances (solver.rtol) or BDF2 may help"
                )
            }
        }
    }
}

/// The driver's own limits, checked after every step: a stop request, the wall-clock
/// budget, `max_steps` steps between two output times, and the stall rule: a run stops
/// when its last [`STALL_STEPS`] steps together advanced less than [`STALL_FRACTION`] ×
/// [`STALL_STEPS`] output intervals, i.e. their mean step is below 1e-4 of the regular
/// output interval t_end / n_times (12.5 ms on the paper's scenes, 50 µs on the 200-s
/// test cases), and moved the solution by less than [`STALL_PATH`] tolerance units
/// ([`Stats::path`]): short steps held back by something other than accuracy. Short
/// steps that move the solution are a motion the model makes (a snap-through, a
/// landing's ringing with inertia on) and are followed, within `max_steps`.
struct StepGuard {
    stop: StopFlag,
    start: Instant,
    budget: Option<f64>,
    max_steps: u64,
    threshold: f64,
    steps_in_interval: u64,
    tout: f64,
    /// (t, error-test failures, Newton failures, path) after each of the last steps.
    window: std::collections::VecDeque<(f64, u64, u64, f64)>,
}

impl StepGuard {
    fn new(stop: StopFlag, budget: Option<f64>, max_steps: u64, output_interval: f64) -> Self {
        Self {
            stop,
            start: Instant::now(),
            budget,
            max_steps,
            threshold: STALL_FRACTION * output_interval,
            steps_in_interval: 0,
            tout: 0.0,
            window: std::collections::VecDeque::with_capacity(STALL_STEPS + 1),
        }
    }

    /// A new output interval starts towards `tout`.
    fn next_output(&mut self, tout: f64) {
        self.tout = tout;
        self.steps_in_interval = 0;
    }

    /// Checks the limits after a step to `t` (`s`: statistics of the whole run so far).
    fn check(&mut self, t: f64, s: &Stats) -> Option<StopCause> {
        self.steps_in_interval += 1;
        if let Some(sig) = self.stop.signal() {
            return Some(StopCause::Signal(sig));
        }
        if let Some(limit) = self.budget {
            if self.start.elapsed().as_secs_f64() > limit {
                return Some(StopCause::Budget(limit));
            }
        }
        if self.steps_in_interval > self.max_steps {
            return Some(StopCause::StepLimit {
                max_steps: self.max_steps,
                tout: self.tout,
            });
        }
        self.window
            .push_back((t, s.error_test_failures, s.newton_failures, s.path));
        if self.window.len() > STALL_STEPS {
            let (t0, etf0, nf0, p0) = self.window.pop_front().unwrap_or((t, 0, 0, s.path));
            let advanced = t - t0;
            let path = s.path - p0;
            if advanced < self.threshold * STALL_STEPS as f64 && path < STALL_PATH {
                return Some(StopCause::Stalled {
                    threshold: self.threshold,
                    advanced,
                    h: s.last_step,
                    order: s.last_order,
                    error_test_failures: s.error_test_failures.saturating_sub(etf0),
                    newton_failures: s.newton_failures.saturating_sub(nf0),
                    path,
                });
            }
        }
        None
    }
}

impl StopCause {
    /// The failure kind this stop is recorded as.
    pub fn kind(&self) -> FailureKind {
        match self {
            StopCause::Signal(_) => FailureKind::Interrupted,
            StopCause::Budget(_) => FailureKind::Budget,
            StopCause::StepLimit { .. } => FailureKind::StepLimit,
            StopCause::Stalled { .. } => FailureKind::Stalled,
        }
    }
}

/// Options of one run.
#[derive(Clone)]
pub struct RunOptions {
    /// Output directory.
    pub out: PathBuf,
    /// The solver settings: the case's `solver` section (`case.solver.clone()`), or what a
    /// study makes of it.
    pub settings: Settings,
    /// The run's own limits (not case fields).
    pub limits: Limits,
    /// Progress display.
    pub progress: Progress,
    /// Set to stop the run cleanly (SIGINT, SIGTERM, SIGHUP).
    pub interrupt: StopFlag,
    /// Per-output-time files besides the CSV row (`--vtu`, `--gif`).
    pub snapshots: SnapshotOptions,
}

impl RunOptions {
    /// A run into `out` with `settings` (a case's `solver` section, say), no limits, no
    /// progress display, no per-output-time files, stopped by nothing but its end.
    pub fn new(out: impl Into<PathBuf>, settings: Settings) -> Self {
        Self {
            out: out.into(),
            settings,
            limits: Limits::default(),
            progress: Progress::Hidden,
            interrupt: StopFlag::default(),
            snapshots: SnapshotOptions::default(),
        }
    }
}

/// A run that could not start or could not finish.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The mesh could not be generated.
    #[error("{file}: mesh: {source}")]
    Mesh {
        /// Case file.
        file: String,
        /// Cause.
        source: MeshError,
    },
    /// The case has a problem the schema could not see.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The model could not be built.
    #[error("{file}: model: {message}")]
    Model {
        /// Case file.
        file: String,
        /// Cause.
        message: String,
    },
    /// An output could not be written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// File.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// A VTU or GIF output could not be written.
    #[error(transparent)]
    Output(#[from] crate::render::OutputError),
    /// The integration stopped; the summary (with the reason) was written.
    #[error("{case}: integration stopped: {reason}")]
    Integration {
        /// Case name.
        case: String,
        /// Why.
        reason: String,
        /// The summary as written.
        summary: Box<Summary>,
    },
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::Io {
        path: path.display().to_string(),
        source,
    }
}

fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), RunError> {
    run_files::write_json(path, value).map_err(io_err(path))
}

/// Output times: `n` equally spaced in (0, t_end], plus the phase ends and the inertia
/// switch (so states are written exactly there), sorted.
pub fn output_times(case: &Case) -> Vec<f64> {
    let ph = &case.phases;
    let n = case.output.n_times.max(1) as usize;
    let mut t: Vec<f64> = (1..=n).map(|k| ph.t_end * k as f64 / n as f64).collect();
    for extra in [ph.t_g0, ph.t_as0, ph.t_a0] {
        if extra < ph.t_end {
            t.push(extra);
        }
    }
    if let InertiaMode::OffAfter(ts) = case.inertia.mode {
        if ts < ph.t_end {
            t.push(ts);
        }
    }
    t.sort_by(f64::total_cmp);
    t.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * ph.t_end);
    t
}

/// Either integrator on the cell model.
enum Solver {
    Ida(Box<Ida<Cell>>),
    Bdf2(Box<Bdf2<Cell>>),
}

impl Solver {
    fn new(model: Cell, s: &Settings, limits: &Limits) -> Result<Self, IntegratorError> {
        let atol = Atol::Vector(model.atol_vector(s.atol));
        // The condensed solver needs the (u, v) pairs: without inertia, its full-size LU.
        let linear_solver = if model.first_order_blocks().is_some() {
            s.linear_solver
        } else {
            s.linear_solver.uncondensed()
        };
        Ok(match s.integrator {
            solver::Integrator::Ida => {
                let opts = ida_options(s, atol, linear_solver);
                Solver::Ida(Box::new(Ida::new(model, opts)?))
            }
            solver::Integrator::Bdf2 => {
                let opts = bdf2_options(s, limits, model.inertia(), atol, linear_solver);
                Solver::Bdf2(Box::new(Bdf2::new(model, opts)?))
            }
        })
    }

    fn integ(&mut self) -> &mut dyn Integrator {
        match self {
            Solver::Ida(i) => i.as_mut(),
            Solver::Bdf2(b) => b.as_mut(),
        }
    }

    fn integ_ref(&self) -> &dyn Integrator {
        match self {
            Solver::Ida(i) => i.as_ref(),
            Solver::Bdf2(b) => b.as_ref(),
        }
    }

    fn model(&self) -> &Cell {
        match self {
            Solver::Ida(i) => i.dae(),
            Solver::Bdf2(b) => b.dae(),
        }
    }
}

/// IDA's options for a run: every field from the settings `s`, or none where IDA's own
/// behaviour is meant (no largest step, no constraints, IDA's failure counts).
fn ida_options(s: &Settings, atol: Atol, linear_solver: solver::LinearSolver) -> IdaOptions {
    IdaOptions {
        rtol: s.rtol,
        atol,
        max_order: s.max_order,
        init_step: s.initial_step,
        max_step: None,
        max_steps: s.max_steps as i64,
        suppress_alg: false,
        calc_ic: None,
        linear_solver: linear_solver.into(),
        constraints: None,
        max_newton_iters: Some(s.newton_iters as i32),
        max_conv_fails: None,
        max_err_test_fails: None,
        delta_cj: Some(s.delta_cj),
        krylov: s.krylov.map(|k| Krylov {
            max_dim: k.max_dim as i32,
            eps_lin: k.eps_lin,
        }),
        nonlinear: s.nonlinear,
    }
}

/// BDF2's options for a run: its step `bdf2_dt` (capped by `limits.dt_inertia` while the
/// system has inertia), the tolerances and the LU from the settings `s`; the method's own
/// constants, which no setting changes, BDF2's defaults.
fn bdf2_options(
    s: &Settings,
    limits: &Limits,
    inertia: bool,
    atol: Atol,
    linear_solver: solver::LinearSolver,
) -> Bdf2Options {
    let dt = match limits.dt_inertia {
        Some(h) if inertia => s.bdf2_dt.min(h),
        _ => s.bdf2_dt,
    };
    Bdf2Options {
        dt,
        rtol: s.rtol,
        atol,
        linear_solver: linear_solver.into(),
        ..Bdf2Options::default()
    }
}

/// A progress bar for a scene (hidden when `visible` is false).
pub fn progress_bar(case: &Case, visible: bool) -> ProgressBar {
    progress_bar_in(case, visible, None)
}

/// As [`progress_bar`], as one line of `multi` when given (several scenes at once).
pub fn progress_bar_in(
    case: &Case,
    visible: bool,
    multi: Option<&indicatif::MultiProgress>,
) -> ProgressBar {
    progress_bar_labelled(&case.name, case.phases.t_end, visible, multi)
}

/// As [`progress_bar_in`], for a stretch of simulated time up to `t_end` shown as `label`
/// (several cases computed together: [`run_all`]).
pub fn progress_bar_labelled(
    label: &str,
    t_end: f64,
    visible: bool,
    multi: Option<&indicatif::MultiProgress>,
) -> ProgressBar {
    if !visible {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new((t_end * 1000.0).round().max(1.0) as u64);
    // Joined to `multi` before styling, so nothing is drawn outside it.
    let pb = match multi {
        Some(m) => m.add(pb),
        None => pb,
    };
    let style = ProgressStyle::with_template(
        "{prefix:>18} [{bar:28}] {percent:>3}% {elapsed_precise} {msg}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar())
    .progress_chars("=> ");
    pb.set_style(style);
    pb.set_prefix(label.to_string());
    pb
}

/// Runs one scene; see the module documentation.
pub fn run(case: &Case, file: &str, opts: &RunOptions) -> Result<Summary, RunError> {
    let member = Member {
        case,
        file,
        opts: opts.clone(),
    };
    let progress = |_: &str, _: f64| opts.progress.clone();
    let mut results = run_all(&[member], 1, false, &progress, &|_, _| {});
    results.pop().unwrap_or_else(|| {
        Err(RunError::Model {
            file: file.into(),
            message: "not run".into(),
        })
    })
}

/// The mesh and the cell model of a case, with the system it starts with
/// (`settings.defer_adhesion`: the μ_as unknowns join it at T_g0,
/// [`CellModel::deferring_adhesion`]) and its element loops in parallel or not.
fn build_model(case: &Case, file: &str, settings: &Settings) -> Result<Cell, RunError> {
    let (defer_adhesion, parallel) = (settings.defer_adhesion, settings.parallel_elements);
    let mesh_err = |source| RunError::Mesh {
        file: file.into(),
        source,
    };
    let params = scene::model_params(case, file, scene::starts_with_inertia(case))?;
    let built: Result<Cell, _> = if scene::is_3d(case) {
        let mesh =
            crate::fem::TetMesh::generate(&scene::tet_mesh_params(case)).map_err(mesh_err)?;
        new_model::<Quarter, 3, 10, 30>(params, mesh, defer_adhesion, parallel)
    } else {
        let mesh = Mesh::generate(&scene::mesh_params(case)).map_err(mesh_err)?;
        new_model::<HalfPlane, 2, 6, 12>(params, mesh, defer_adhesion, parallel)
    };
    built.map_err(|e| RunError::Model {
        file: file.into(),
        message: e.to_string(),
    })
}

/// The model of shape `S` on `mesh`, deferring its μ_as unknowns or not, its element loops
/// on the thread pool or not.
fn new_model<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize>(
    params: ModelParams,
    mesh: S::Mesh,
    defer_adhesion: bool,
    parallel: bool,
) -> Result<Cell, ModelError>
where
    CellOf<S, D, N, E>: RunModel,
{
    let mut m = if defer_adhesion {
        CellOf::<S, D, N, E>::deferring_adhesion(params, mesh)?
    } else {
        CellOf::<S, D, N, E>::new(params, mesh)?
    };
    m.set_parallel(parallel);
    Ok(Box::new(m))
}

/// How an advance to an output time ended.
enum Advance {
    /// The output time was reached.
    Reached,
    /// A phase started on its condition (0 adhesion, 1 active) before it, at the
    /// driver's current time: the integrator restarted there.
    Started,
    /// The run stops.
    Stopped(Stop),
}

/// Why a run stops before its end: the kind of stop and its reason, the time it reached
/// and, for a stop at an element, where.
#[derive(Debug, Clone)]
pub(crate) struct Stop {
    /// The kind of stop.
    pub kind: FailureKind,
    /// What happened.
    pub reason: String,
    /// The time of the last accepted step, where the driver knows it \[s\].
    pub t: Option<f64>,
    /// The element, for [`FailureKind::Inverted`].
    pub place: Option<StopPlace>,
}

impl Stop {
    /// A stop of `kind` for `reason`, its time and place not known.
    pub fn new(kind: FailureKind, reason: String) -> Self {
        Self {
            kind,
            reason,
            t: None,
            place: None,
        }
    }
}

/// The integrator on the current system, and what the driver keeps across output times:
/// its limits (`StepGuard`), the progress display and the pending inertia switch.
struct Driver {
    solver: Solver,
    settings: Settings,
    limits: Limits,
    guard: StepGuard,
    reporter: Reporter,
    /// Statistics of the systems before the current one.
    stats_before: Stats,
    /// The requested inertia switch time, while the switch is pending.
    switch_after: Option<f64>,
    /// When inertia was switched off.
    switched_at: Option<f64>,
    /// When the μ_as unknowns join the system (T_g0), while they are deferred.
    adhesion_at: Option<f64>,
    /// When they joined it.
    adhesion_added_at: Option<f64>,
    /// The phases' starts and the conditions watched (MODEL.md §11).
    schedule: events::Schedule,
}

impl Driver {
    fn new(case: &Case, opts: &RunOptions, model: Cell) -> Result<Self, IntegratorError> {
        let ph = &case.phases;
        // The μ_as unknowns join at adhesion's start: a known one before the end, else at
        // the condition's root.
        let adhesion_at = events::Schedule::new(case).starts[0]
            .filter(|&t| model.adhesion_deferred() && t < ph.t_end);
        let solver = Solver::new(model, &opts.settings, &opts.limits)?;
        Ok(Self {
            adhesion_at,
            ..Self::with_solver(case, opts, solver)
        })
    }

    /// The driver of `case` on `solver`, with nothing pending (no inertia switch unless
    /// the case asks for one, no deferred μ_as unknowns).
    fn with_solver(case: &Case, opts: &RunOptions, solver: Solver) -> Self {
        let ph = &case.phases;
        Self {
            solver,
            settings: opts.settings.clone(),
            limits: opts.limits,
            guard: StepGuard::new(
                opts.interrupt.clone(),
                opts.limits.max_wall_seconds,
                opts.settings.max_steps,
                ph.t_end / case.output.n_times.max(1) as f64,
            ),
            reporter: Reporter::new(&opts.progress, ph.t_end),
            stats_before: Stats::default(),
            switch_after: match case.inertia.mode {
                InertiaMode::OffAfter(t) if t < ph.t_end => Some(t),
                _ => None,
            },
            switched_at: None,
            adhesion_at: None,
            adhesion_added_at: None,
            schedule: events::Schedule::new(case),
        }
    }

    /// Shows progress with `progress` from now on (the run's end now `t_end`).
    fn relabel(&mut self, progress: Progress, t_end: f64) {
        self.reporter.finish();
        self.reporter = Reporter::new(&progress, t_end);
    }

    /// The run time of `case`'s end (infinite while it waits for a phase's start).
    fn t_end(&self, case: &Case) -> f64 {
        if self.schedule.is_paper() {
            case.phases.t_end
        } else {
            self.schedule.t_end()
        }
    }

    /// The output times of `case` known now (with the phase starts found so far).
    fn output_times(&self, case: &Case) -> Vec<f64> {
        let nominal = output_times(case);
        if self.schedule.is_paper() {
            nominal
        } else {
            self.schedule.output_times(&nominal)
        }
    }

    /// Statistics of the run so far (all systems).
    fn stats(&self) -> Stats {
        &self.stats_before + &self.solver.integ_ref().stats()
    }

    /// The model and (y, ẏ) at the last output time reached.
    fn state(&self) -> (&Cell, &[f64], &[f64]) {
        let i = self.solver.integ_ref();
        (self.solver.model(), i.y(), i.yp())
    }

    /// Advances to `tout`, switching inertia off on the way once past the requested
    /// switch time and the contact carries the cell.
    fn advance_to(&mut self, tout: f64) -> Advance {
        self.guard.next_output(tout);
        // Why the driver stopped the integrator, and when (the integrator itself only
        // says "interrupted").
        let mut stopped: Option<(StopCause, f64)> = None;
        let result = self.advance_inner(tout, &mut stopped);
        match (stopped, result) {
            (Some((cause, t)), _) => Advance::Stopped(Stop {
                t: Some(t),
                ..Stop::new(cause.kind(), cause.reason(t))
            }),
            (None, Err(reason)) => {
                // Given up: on an inverted element if the last state tried had one.
                let place = self.solver.model().inadmissible_place();
                let kind = match place {
                    Some(_) => FailureKind::Inverted,
                    None => FailureKind::Integration,
                };
                Advance::Stopped(Stop {
                    t: Some(self.solver.integ_ref().last_step().0),
                    place,
                    ..Stop::new(kind, reason)
                })
            }
            (None, Ok(Some(_))) => Advance::Started,
            (None, Ok(None)) => Advance::Reached,
        }
    }

    /// Advances to `tout`, adding the μ_as unknowns on the way at their time; stops early
    /// where a phase starts on its condition (returned).
    fn advance_inner(
        &mut self,
        tout: f64,
        stopped: &mut Option<(StopCause, f64)>,
    ) -> Result<Option<usize>, String> {
        if let Some(ta) = self.adhesion_at {
            if tout >= ta {
                let started = self.advance_system(ta, stopped)?;
                if stopped.is_some() || started.is_some() {
                    return Ok(started);
                }
                self.add_adhesion_unknowns()?;
            }
        }
        self.advance_system(tout, stopped)
    }

    /// At a root of the watched conditions: what it means; at a phase's start, the
    /// integrator restarted there with the phase's ramp from that time (and the μ_as
    /// unknowns added if they wait for adhesion).
    fn on_root(&mut self, root: &crate::dae::Root) -> Result<Option<usize>, String> {
        let integ = self.solver.integ_ref();
        let at = State {
            t: integ.t(),
            y: integ.y(),
            yp: integ.yp(),
        };
        let model = self.solver.model();
        let mut g = vec![0.0; root.crossings.len()];
        model.condition_values(at, &mut g);
        let meaning = self.schedule.on_root(root, |j| g[2 * j + 1]);
        let events::Meaning::Starts(k) = meaning else {
            return Ok(None);
        };
        let t = at.t;
        let params = scene::model_params(self.schedule.case(), "", model.inertia())
            .map_err(|e| e.to_string())?;
        let restart = |e: String| {
            format!(
                "restart where the {} phase starts, t = {t} s: {e}",
                events::PHASES[k]
            )
        };
        let mut m2 = model
            .branched(self.schedule.params(params), at)
            .map_err(|e| restart(e.to_string()))?;
        if k == 0 && m2.adhesion_deferred() {
            m2 = m2
                .with_adhesion_unknowns(at)
                .map_err(|e| restart(e.to_string()))?;
            self.adhesion_added_at = Some(t);
        }
        let mut settings = self.settings.clone();
        let last = integ.stats().last_step;
        if last > 0.0 {
            settings.initial_step = Some(0.1 * last);
        }
        let new = Solver::new(m2, &settings, &self.limits).map_err(|e| restart(e.to_string()))?;
        let old = std::mem::replace(&mut self.solver, new);
        self.stats_before += &old.integ_ref().stats();
        let t_end = self.schedule.t_end();
        if t_end.is_finite() {
            self.reporter.set_end(t_end);
        }
        Ok(Some(k))
    }

    /// Swaps the system for the same one with its μ_as unknowns, at the current time.
    fn add_adhesion_unknowns(&mut self) -> Result<(), String> {
        let integ = self.solver.integ_ref();
        let t = integ.t();
        let at = State {
            t,
            y: integ.y(),
            yp: integ.yp(),
        };
        let m2 = self
            .solver
            .model()
            .with_adhesion_unknowns(at)
            .map_err(|e| e.to_string())?;
        // The solution goes on smoothly: start from a tenth of the last step rather than
        // IDA's estimate (which started 4000× below it and took a dozen steps to regain it).
        let mut settings = self.settings.clone();
        let last = self.solver.integ_ref().stats().last_step;
        if last > 0.0 {
            settings.initial_step = Some(0.1 * last);
        }
        let new = Solver::new(m2, &settings, &self.limits)
            .map_err(|e| format!("restart with the adhesion unknowns at t = {t}: {e}"))?;
        let old = std::mem::replace(&mut self.solver, new);
        self.stats_before += &old.integ_ref().stats();
        self.adhesion_at = None;
        self.adhesion_added_at = Some(t);
        Ok(())
    }

    /// Advances the current system to `tout`, switching inertia off on the way when due,
    /// and stopping where a phase starts on its condition (returned).
    fn advance_system(
        &mut self,
        tout: f64,
        stopped: &mut Option<(StopCause, f64)>,
    ) -> Result<Option<usize>, String> {
        loop {
            self.advance_system_once(tout, stopped)?;
            if stopped.is_some() {
                return Ok(None);
            }
            let Some(root) = self.solver.integ_ref().root().cloned() else {
                return Ok(None);
            };
            if let Some(k) = self.on_root(&root)? {
                return Ok(Some(k));
            }
        }
    }

    /// Advances the current system to `tout` or its first root, switching inertia off on
    /// the way when due.
    fn advance_system_once(
        &mut self,
        tout: f64,
        stopped: &mut Option<(StopCause, f64)>,
    ) -> Result<(), String> {
        let Self {
            solver,
            settings,
            limits,
            guard,
            reporter,
            stats_before,
            switch_after,
            switched_at,
            ..
        } = self;
        if let Some(ts) = *switch_after {
            if solver.integ_ref().t() >= ts {
                let base = stats_before.clone();
                let mut on_step =
                    |t: f64, s: &Stats| after_step(guard, reporter, stopped, &base, t, s);
                match advance_switching(solver, ts, tout, settings, limits, &mut on_step)? {
                    Switch::Switched(old_stats, t_switch) => {
                        *stats_before += &old_stats;
                        *switched_at = Some(t_switch);
                        *switch_after = None;
                    }
                    Switch::Root => return Ok(()),
                    Switch::Reached => {}
                }
            }
        }
        let base = stats_before.clone();
        let mut on_step = |t: f64, s: &Stats| after_step(guard, reporter, stopped, &base, t, s);
        solver
            .integ()
            .advance_to(tout, &mut on_step)
            .map_err(|e| e.to_string())?;
        Ok(())
    }

    /// Why the run must stop if the inertia switch is still pending
    /// [`SWITCH_PROBE_LIMIT`] after its requested time.
    fn switch_overdue(&self) -> Option<String> {
        let ts = self.switch_after?;
        (self.solver.integ_ref().t() - ts > SWITCH_PROBE_LIMIT).then(|| {
            format!(
                "cannot switch inertia off: in the {SWITCH_PROBE_LIMIT} s after t = {ts} s the contact never carried the cell's weight"
            )
        })
    }

    fn finish(&self) {
        self.reporter.finish();
    }
}

/// The per-output-time writers of a run's model.
enum Frames {
    Plane(SnapshotWriter),
    Quarter(QuarterSnapshotWriter),
}

/// Why an output could not be written at an output time.
enum OutputStop {
    /// The state or its observables are not finite (nothing written): the run stops.
    NonFinite(f64),
    /// The state left the scene (nothing written): the run stops with this reason.
    Unphysical(String),
    /// The state at an output time could not be formed (the reason): the run stops.
    State(f64, String),
    /// Elements folded inside at an output time (det F ≤ 0 at a point of the band rule,
    /// between the solid rule's points; nothing written): the run stops, classified
    /// inverted. The contact takes J₊ at such points so that a crease's tip can pass
    /// between outputs (docs/MODEL.md §5); a state that keeps them is not reported.
    Folded(f64, crate::model::observe::Folded),
    /// A file could not be written: the run fails with this error.
    Io(RunError),
}

impl OutputStop {
    /// The stop this makes, or the error to return at once.
    fn into_stop(self) -> Result<Stop, RunError> {
        match self {
            OutputStop::NonFinite(t) => Ok(Stop::new(
                FailureKind::Integration,
                format!("non-finite state or output at t = {t} s (not written)"),
            )),
            OutputStop::Unphysical(why) => Ok(Stop::new(FailureKind::Unphysical, why)),
            OutputStop::Folded(t, f) => {
                let point = format!("band point {}", f.point);
                // A folded element was looked at point by point: the smallest is known.
                let smallest = f.smallest.unwrap_or(f64::NAN);
                let mut stop = Stop::new(
                    FailureKind::Inverted,
                    format!(
                        "{} element(s) folded inside at t = {t} s (not written): det F = {:.3e} \
                         at {point} of element {}, between the solid rule's points \
                         (docs/MODEL.md §5); the mesh does not resolve the deformation there",
                        f.folded, smallest, f.element
                    ),
                );
                stop.t = Some(t);
                stop.place = Some(StopPlace {
                    element: f.element,
                    domain: f.domain,
                    point,
                    quantity: "det F".into(),
                    value: smallest,
                    t,
                    x: f.x,
                });
                Ok(stop)
            }
            OutputStop::State(t, why) => Ok(Stop::new(
                FailureKind::Integration,
                format!("cannot form the state at t = {t} s: {why}"),
            )),
            OutputStop::Io(e) => Err(e),
        }
    }
}

impl From<RunError> for OutputStop {
    fn from(e: RunError) -> Self {
        OutputStop::Io(e)
    }
}

impl From<crate::render::OutputError> for OutputStop {
    fn from(e: crate::render::OutputError) -> Self {
        OutputStop::Io(RunError::Output(e))
    }
}

/// Longest wall time between two writes of a running run's summary (each is a JSON file
/// written and renamed into place: after every one of 400 rows it cost a tenth of a short
/// run).
pub const SUMMARY_INTERVAL: Duration = Duration::from_millis(500);

/// How far any point of the cell can move in a scene \[µm\]: the cell's diameter plus the
/// height of its lowest point above the substrate's lowest point (the floor between the
/// pillars). A state past it has left the scene: a displacement no force of the model
/// can cause, seen only where the integrator's tolerances let the error test pass
/// nonsense (`--rtol 0.5` once sent the cell 13 cm up with exit 0).
pub fn scene_reach(case: &Case) -> f64 {
    let g = &case.geometry;
    let floor = match &case.substrate {
        case::Substrate::Flat(f) => f.y_s,
        case::Substrate::Pillars(p) => p.resolved_y_top(g) - p.height,
    };
    2.0 * g.r_c + (g.centre_y - g.r_c - floor).max(0.0)
}

/// Why the state `y` at `t` is not one a run may report: a node moved further than
/// `reach` ([`scene_reach`]).
fn unphysical(model: &Cell, t: f64, y: &[f64], reach: f64) -> Option<String> {
    let (node, moved) = model.largest_displacement(y);
    (moved > reach).then(|| {
        format!(
            "unphysical state at t = {t:.6e} s (not written): node {node} moved {moved:.4e} µm,              more than the cell's diameter plus its height above the substrate's lowest point              ({reach} µm); the tolerances (solver.rtol, solver.atol) let the error test pass a              state the model cannot reach"
        )
    })
}

/// The observables of `model` at (`t`, `y`), refused when they or `y` are not finite (not
/// expected: the residual reports non-finite values as inadmissible, and the integrators
/// cut the step, but a run must never write NaN) or when the state has left the scene
/// (a node moved further than `reach`, [`scene_reach`]).
fn observe_admissible(
    model: &Cell,
    t: f64,
    y: &[f64],
    reach: f64,
) -> Result<(Observables, Option<crate::run_files::QuarterObservables>), OutputStop> {
    let (obs, obs3) = model.observe(t, y);
    if !obs.is_finite() || obs3.is_some_and(|o| !o.is_finite()) || y.iter().any(|v| !v.is_finite())
    {
        return Err(OutputStop::NonFinite(t));
    }
    if let Some(why) = unphysical(model, t, y, reach) {
        return Err(OutputStop::Unphysical(why));
    }
    Ok((obs, obs3))
}

/// The files of a run, written as it goes: `mesh.json` first, a `timeseries.csv` row (and
/// with `--vtu`/`--gif` a snapshot) per output time, `state_<phase>.json` at phase ends,
/// and `summary.json` at most every [`SUMMARY_INTERVAL`] of wall time (and at each state file) and at the end.
struct RunWriter {
    out: PathBuf,
    csv_path: PathBuf,
    csv: BufWriter<File>,
    /// The VTU and GIF writers.
    frames: Frames,
    phase_states: bool,
    phases: [(f64, &'static str); 4],
    tolerance: f64,
    /// How far a node may move before the state is unphysical ([`scene_reach`]).
    reach: f64,
    summary: Summary,
    /// When the summary was last written.
    summary_written: Option<Instant>,
    /// State files listed in the summary last written.
    states_in_summary: usize,
}

impl RunWriter {
    /// Creates the directory, writes `mesh.json` and the CSV header, and starts the summary.
    fn create(case: &Case, file: &str, opts: &RunOptions, model: &Cell) -> Result<Self, RunError> {
        let out = opts.out.clone();
        std::fs::create_dir_all(&out).map_err(io_err(&out))?;
        let ph = &case.phases;
        let phase_times = [ph.t_g0, ph.t_as0, ph.t_a0, ph.t_end];
        let n_outputs = output_times(case).len() + 1;
        let (frames, header) = match model.view() {
            ModelView::Plane(m) => {
                let (mesh, params) = (&m.mesh, &m.params);
                let mesh_file = MeshFile {
                    nodes: mesh.nodes.clone(),
                    elements: mesh.elements.clone(),
                    domains: mesh.domains.clone(),
                    outer_edges: mesh.outer_edges.clone(),
                    nucleus_edges: mesh.nucleus_edges.clone(),
                    membrane_inner_edges: mesh.membrane_inner_edges.clone(),
                    substrate: params.substrate,
                    active: params.active,
                    contact_eps: params.contact.eps,
                    layer_thickness: params.adhesion.map(|a| a.e_f),
                    center: params.center,
                    phase_times,
                };
                write_json(&out.join("mesh.json"), &mesh_file)?;
                let frames =
                    SnapshotWriter::new(&out, &case.name, &mesh_file, opts.snapshots, n_outputs)?;
                (Frames::Plane(frames), Observables::CSV_HEADER.to_string())
            }
            ModelView::Quarter(m) => {
                let mesh_file = m.mesh_file(phase_times);
                write_json(&out.join("mesh3.json"), &mesh_file)?;
                let frames = QuarterSnapshotWriter::new(
                    &out,
                    &case.name,
                    &mesh_file,
                    opts.snapshots,
                    n_outputs,
                )?;
                let header = format!(
                    "{},{}",
                    Observables::CSV_HEADER,
                    crate::run_files::QuarterObservables::CSV_COLUMNS
                );
                (Frames::Quarter(frames), header)
            }
        };
        let csv_path = out.join("timeseries.csv");
        let mut csv = BufWriter::new(File::create(&csv_path).map_err(io_err(&csv_path))?);
        writeln!(csv, "{header}").map_err(io_err(&csv_path))?;
        let (nu, nv, nm) = model.unknowns();
        let (mesh_elements, mesh_nodes) = model.mesh_size();
        let summary = Summary {
            case: case.name.clone(),
            case_file: file.to_string(),
            settings: SettingsUsed {
                solver: opts.settings.clone(),
                limits: opts.limits,
            },
            inertia: format!("{:?}", case.inertia.mode),
            unknowns: Unknowns {
                total: nu + nv + nm,
                u: nu,
                v: nv,
                mu_as: nm,
            },
            mesh_elements,
            mesh_nodes,
            wall_seconds: 0.0,
            setup_seconds: 0.0,
            stats: Stats::default(),
            finished: false,
            failure: None,
            final_values: None,
            final_values_3d: None,
            strain_nucleus_max: None,
            folded_elements: None,
            outputs: 0,
            inertia_switched_off_at: None,
            adhesion_unknowns_added_at: None,
            events: Vec::new(),
            phase_times: None,
            shared: Vec::new(),
            states: Vec::new(),
            cellsim_version: env!("CARGO_PKG_VERSION").to_string(),
            sundials_version: crate::sundials::SUNDIALS_VERSION.to_string(),
            timers: None,
        };
        let mut writer = Self {
            out,
            csv_path,
            csv,
            frames,
            phase_states: case.output.phase_states,
            phases: [
                (ph.t_end, "end"),
                (ph.t_g0, "gravity"),
                (ph.t_as0, "spreading"),
                (ph.t_a0, "active"),
            ],
            tolerance: 1e-9 * ph.t_end,
            reach: scene_reach(case),
            summary,
            summary_written: None,
            states_in_summary: 0,
        };
        let schedule = events::Schedule::new(case);
        if !schedule.is_paper() {
            writer.set_schedule(&schedule);
        }
        Ok(writer)
    }

    /// The phase ends and the summary's events and phase lines as the schedule knows them
    /// (a run whose cell starts phases itself).
    fn set_schedule(&mut self, schedule: &events::Schedule) {
        let [end, gravity, spreading, active] = schedule.phase_ends();
        self.phases = [
            (end, "end"),
            (gravity, "gravity"),
            (spreading, "spreading"),
            (active, "active"),
        ];
        self.summary.events = schedule.events();
        self.summary.phase_times = Some(
            schedule
                .phase_times()
                .map(|t| if t.is_finite() { Some(t) } else { None }),
        );
    }

    /// The phase that ends at `t`, if any.
    fn phase_at(&self, t: f64) -> Option<&'static str> {
        self.phases
            .iter()
            .find(|(tp, _)| (tp - t).abs() <= self.tolerance)
            .map(|(_, name)| *name)
    }

    /// Writes everything due at output time `t`: the CSV row, a snapshot, and at a phase
    /// end the state file. Nothing is written for a non-finite state.
    fn output(&mut self, model: &Cell, t: f64, y: &[f64], yp: &[f64]) -> Result<(), OutputStop> {
        let (obs, obs3) = observe_admissible(model, t, y, self.reach)?;
        let folded = match model.view() {
            ModelView::Plane(m) => m.folded_elements(y),
            ModelView::Quarter(m) => m.folded_elements(y),
        };
        self.summary.folded_elements = Some((folded.folded, folded.smallest));
        if folded.folded > 0 {
            return Err(OutputStop::Folded(t, folded));
        }
        let mut row = obs.csv_row();
        if let Some(o3) = &obs3 {
            for v in o3.values() {
                row.push(',');
                row.push_str(&v.to_string());
            }
        }
        writeln!(self.csv, "{row}")
            .and_then(|_| self.csv.flush())
            .map_err(io_err(&self.csv_path))?;
        self.summary.outputs += 1;
        self.summary.final_values = Some(obs);
        self.summary.final_values_3d = obs3;
        self.summary.strain_nucleus_max = Some(match model.view() {
            ModelView::Plane(m) => m.largest_strain_norm(y, Domain::Nucleus),
            ModelView::Quarter(m) => m.largest_strain_norm(y, Domain::Nucleus),
        });
        match (model.view(), &mut self.frames) {
            (ModelView::Plane(m), Frames::Plane(frames)) if frames.is_active() => {
                let mu_as = m
                    .nodal_mu_as(t, y)
                    .map_err(|why| OutputStop::State(t, why.to_string()))?;
                frames.write(&snapshot(m, t, y, yp, mu_as))?;
            }
            (ModelView::Quarter(m), Frames::Quarter(frames)) if frames.is_active() => {
                let snap = m
                    .snapshot(t, y, yp)
                    .map_err(|why| OutputStop::State(t, why.to_string()))?;
                frames.write(&snap)?;
            }
            _ => {}
        }
        if let Some(phase) = self.phase_at(t).filter(|_| self.phase_states && t > 0.0) {
            self.write_state(model, phase, t, y, yp, obs, obs3)?;
        }
        Ok(())
    }

    /// Writes `state_<phase>.json`, the state at `t` with its observables, and lists it in
    /// the summary.
    #[allow(clippy::too_many_arguments)]
    fn write_state(
        &mut self,
        model: &Cell,
        phase: &str,
        t: f64,
        y: &[f64],
        yp: &[f64],
        obs: Observables,
        obs3: Option<crate::run_files::QuarterObservables>,
    ) -> Result<(), OutputStop> {
        let name = format!("state_{phase}.json");
        let path = self.out.join(&name);
        match (model.view(), obs3) {
            (ModelView::Plane(m), _) => {
                let mu_as = m
                    .nodal_mu_as(t, y)
                    .map_err(|why| OutputStop::State(t, why.to_string()))?;
                write_json(&path, &state_file(m, phase, t, y, mu_as, obs))?;
            }
            (ModelView::Quarter(m), Some(observables3)) => {
                let state = crate::run_files::QuarterStateFile {
                    phase: phase.to_string(),
                    state: m
                        .snapshot(t, y, yp)
                        .map_err(|why| OutputStop::State(t, why.to_string()))?,
                    observables: obs,
                    observables3,
                };
                write_json(&path, &state)?;
            }
            (ModelView::Quarter(_), None) => {
                return Err(OutputStop::State(t, "no 3-D observables".into()));
            }
        }
        self.summary.states.push(name);
        Ok(())
    }

    /// Writes `state_stopped.json`: where a run that stops before its end got to (`t`,
    /// `y`, `ẏ`: its last accepted step, usually past the last output time), so that the
    /// state at a failure can be looked at and plotted. Nothing is written for a
    /// non-finite state, nor when the case turned the state files off.
    fn stopped_state(
        &mut self,
        model: &Cell,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<(), OutputStop> {
        if !self.phase_states {
            return Ok(());
        }
        let (obs, obs3) = observe_admissible(model, t, y, self.reach)?;
        self.write_state(model, STOPPED, t, y, yp, obs, obs3)
    }

    fn write_summary(&mut self) -> Result<(), RunError> {
        self.summary_written = Some(Instant::now());
        write_json(&self.out.join("summary.json"), &self.summary)
    }

    /// Writes the summary after an output time if it is due: at most every
    /// [`SUMMARY_INTERVAL`] of wall time, and whenever a state file was written (the rows
    /// themselves are in the CSV, flushed at once; the final summary is always written).
    fn write_summary_if_due(&mut self) -> Result<(), RunError> {
        let due = self.summary.states.len() != self.states_in_summary
            || self
                .summary_written
                .is_none_or(|t| t.elapsed() >= SUMMARY_INTERVAL);
        if due {
            self.states_in_summary = self.summary.states.len();
            self.write_summary()?;
        }
        Ok(())
    }

    /// Closes the snapshot files and writes the final summary: finished, or the stop's
    /// kind and reason with the statistics up to the last step.
    fn finish(
        self,
        case: &Case,
        stats: Stats,
        wall: f64,
        mut stopped: Option<Stop>,
    ) -> Result<Summary, RunError> {
        let RunWriter {
            out,
            frames,
            mut summary,
            ..
        } = self;
        summary.wall_seconds = wall;
        if crate::dae::timing::ENABLED {
            summary.timers = Some(TimeBreakdown::from_totals(
                &crate::dae::timing::totals(),
                wall,
            ));
        }
        let finished = match frames {
            Frames::Plane(f) => f.finish(),
            Frames::Quarter(f) => f.finish(),
        };
        if let Err(e) = finished {
            stopped.get_or_insert(Stop::new(
                FailureKind::Output,
                format!("writing the VTU/GIF output: {e}"),
            ));
        }
        let path = out.join("summary.json");
        match stopped {
            None => {
                summary.finished = true;
                write_json(&path, &summary)?;
                Ok(summary)
            }
            Some(Stop {
                kind,
                reason,
                t,
                place,
            }) => {
                // The statistics up to the failing step (not only up to the last output).
                summary.stats = stats;
                summary.failure = Some(Failure {
                    kind,
                    reason: reason.clone(),
                    t_last_output: summary.final_values.map(|o| o.t).unwrap_or(0.0),
                    step: summary.stats.steps,
                    t_stop: t,
                    place,
                });
                write_json(&path, &summary)?;
                Err(RunError::Integration {
                    case: case.name.clone(),
                    reason,
                    summary: Box::new(summary),
                })
            }
        }
    }
}

/// What the driver does after every step of either integrator (`s`: the statistics of
/// the current integrator, `base`: those of the systems before it): check its limits and
/// show progress. Returns false to stop the integrator, the cause recorded in `stopped`.
fn after_step(
    guard: &mut StepGuard,
    reporter: &mut Reporter,
    stopped: &mut Option<(StopCause, f64)>,
    base: &Stats,
    t: f64,
    s: &Stats,
) -> bool {
    let total = base + s;
    if let Some(cause) = guard.check(t, &total) {
        *stopped = Some((cause, t));
        return false;
    }
    reporter.step(t, &total);
    true
}

/// How [`advance_switching`] ended.
enum Switch {
    /// Inertia switched off: the old integrator's statistics and the switch time.
    Switched(Stats, f64),
    /// The output time came first.
    Reached,
    /// A root of the watched conditions came first (the integrator stopped there).
    Root,
}

/// Longest stretch watched with inertia, after the requested switch time, for the moment
/// the contact carries the cell \[s\].
pub(crate) const SWITCH_PROBE_LIMIT: f64 = 50.0;

/// Advances towards `tout` one step at a time and, at the first accepted step at or after
/// the requested switch time `ts` where the contact carries the cell's current weight,
/// switches inertia off: the same model on (u, μ_as), restarted at that step at rest in
/// equilibrium ([`CellModel::without_inertia_at_rest`]). Every step is looked at, not a
/// grid of times: after a fall of several µm the cell bounces, and its impacts last
/// microseconds (`cases/hard/gap-large.ron`), between which it is in the air and cannot be
/// set at rest on the substrate. The steps do not depend on the output times, so runs with
/// other outputs switch at the same moment. Returns the old integrator's statistics and
/// the switch time once switched, or whether `tout` or a root of the watched conditions
/// came first.
fn advance_switching(
    solver: &mut Solver,
    ts: f64,
    tout: f64,
    settings: &Settings,
    limits: &Limits,
    on_step: &mut dyn FnMut(f64, &Stats) -> bool,
) -> Result<Switch, String> {
    loop {
        let integ = solver.integ_ref();
        let (t, y, yp) = integ.last_step();
        // A step past `tout` is looked at in the next output interval (the driver first
        // needs the state at `tout`, interpolated by this integrator).
        if t >= ts && t <= tout && solver.model().contact_carries_weight(t, y) {
            let restart = Restart {
                linear_solver: &settings.linear_solver.uncondensed(),
                rtol: settings.rtol,
                atol: settings.atol,
            };
            let m2 = solver
                .model()
                .without_inertia_at_rest(State { t, y, yp }, &restart)
                .map_err(|e| e.to_string())?;
            let new = Solver::new(m2, settings, limits)
                .map_err(|e| format!("restart without inertia at t = {t}: {e}"))?;
            let old = std::mem::replace(solver, new);
            return Ok(Switch::Switched(old.integ_ref().stats(), t));
        }
        if integ.t() >= tout {
            return Ok(Switch::Reached);
        }
        // One step (or the interpolation to `tout` once a step is past it).
        let mut driver_stop = false;
        let mut one_step = |t: f64, s: &Stats| {
            driver_stop = !on_step(t, s);
            false
        };
        match solver.integ().advance_to(tout, &mut one_step) {
            Ok(()) if solver.integ_ref().root().is_some() => return Ok(Switch::Root),
            Ok(()) => {}
            Err(IntegratorError::Interrupted { .. }) if !driver_stop => {}
            Err(e) => return Err(e.to_string()),
        }
    }
}

/// The state at one output time for the VTU and GIF writers: velocities are the v
/// unknowns with inertia, u̇ (from `yp`) without.
fn snapshot(model: &CellModel, t: f64, y: &[f64], yp: &[f64], mu_as: Vec<Option<f64>>) -> Snapshot {
    let n = model.mesh.nodes.len();
    let per_el = model.element_strain_and_jacobian(y);
    let d = &model.dofs;
    Snapshot {
        t,
        u: (0..n).map(|i| d.node_u(y, i)).collect(),
        v: (0..n).map(|i| d.node_velocity(y, yp, i)).collect(),
        mu_as,
        element_strain: per_el.iter().map(|p| p.0).collect(),
        element_jacobian: per_el.iter().map(|p| p.1).collect(),
    }
}

fn state_file(
    model: &CellModel,
    phase: &str,
    t: f64,
    y: &[f64],
    mu_as: Vec<Option<f64>>,
    observables: Observables,
) -> StateFile {
    let n = model.mesh.nodes.len();
    let per_el = model.element_strain_and_jacobian(y);
    StateFile {
        phase: phase.to_string(),
        t,
        u: (0..n).map(|i| model.dofs.node_u(y, i)).collect(),
        mu_as,
        element_strain: per_el.iter().map(|p| p.0).collect(),
        element_jacobian: per_el.iter().map(|p| p.1).collect(),
        observables,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(steps: u64, h: f64) -> Stats {
        Stats {
            steps,
            last_step: h,
            last_order: 2,
            ..Stats::default()
        }
    }

    #[test]
    fn step_guard_stops_a_collapsed_step_but_not_a_fast_one() {
        // Output interval 1 s: threshold 1e-4 s on the mean step.
        let mut g = StepGuard::new(StopFlag::new(), None, u64::MAX, 1.0);
        g.next_output(1e9);
        // Steps of 2e-4 s: never a stall.
        let mut t = 0.0;
        for k in 0..3 * STALL_STEPS as u64 {
            t += 2e-4;
            assert_eq!(g.check(t, &stats(k, 2e-4)), None, "step {k}");
        }
        // Then steps of 1e-6 s: the mean over the window falls below 1e-4 s after about
        // half a window, and the stall is reported with what the window advanced.
        let mut stopped = None;
        for k in 0..STALL_STEPS as u64 {
            t += 1e-6;
            if let Some(c) = g.check(t, &stats(k, 1e-6)) {
                stopped = Some((k, c));
                break;
            }
        }
        let (k, cause) = stopped.expect("stall detected");
        assert!(
            k > STALL_STEPS as u64 / 3 && k < STALL_STEPS as u64,
            "after {k} steps"
        );
        match cause {
            StopCause::Stalled {
                threshold,
                advanced,
                ..
            } => {
                assert_eq!(threshold, 1e-4);
                assert!(advanced < threshold * STALL_STEPS as f64, "{advanced}");
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn short_steps_that_move_the_solution_are_not_a_stall() {
        // Output interval 1 s: steps of 1e-6 s, far below the 1e-4 s threshold. Each moves
        // the solution by 2 tolerance units (a fast motion: no stall, however long), then
        // by 0.5 (a step held back by Newton failures: a stall within a window).
        let mut g = StepGuard::new(StopFlag::new(), None, u64::MAX, 1.0);
        g.next_output(1e9);
        let (mut t, mut path) = (0.0, 0.0);
        for k in 0..3 * STALL_STEPS as u64 {
            t += 1e-6;
            path += 2.0;
            let s = Stats {
                path,
                ..stats(k, 1e-6)
            };
            assert_eq!(g.check(t, &s), None, "step {k}");
        }
        let mut stopped = None;
        for k in 0..2 * STALL_STEPS as u64 {
            t += 1e-6;
            path += 0.5;
            if let Some(c) = g.check(
                t,
                &Stats {
                    path,
                    ..stats(k, 1e-6)
                },
            ) {
                stopped = Some((k, c));
                break;
            }
        }
        let (k, cause) = stopped.expect("stall detected");
        // The window's path falls below STALL_PATH = 1 000 units once two thirds of it
        // are the slow steps.
        assert!(
            k > STALL_STEPS as u64 / 2 && k < STALL_STEPS as u64,
            "after {k} steps"
        );
        match &cause {
            StopCause::Stalled { path, .. } => assert!(*path < STALL_PATH, "{path}"),
            other => panic!("{other:?}"),
        }
        let reason = cause.reason(1.0);
        for needle in [
            "stalled at t = ",
            "tolerance units",
            "last step h = ",
            "failures in",
        ] {
            assert!(reason.contains(needle), "{reason}");
        }
    }

    #[test]
    fn step_guard_enforces_max_steps_per_output_interval_and_the_stop_flag() {
        let stop = StopFlag::new();
        let mut g = StepGuard::new(stop.clone(), None, 3, 1.0);
        g.next_output(1.0);
        for k in 0..3 {
            assert_eq!(g.check(0.1 * k as f64, &stats(k, 0.1)), None);
        }
        assert!(matches!(
            g.check(0.4, &stats(3, 0.1)),
            Some(StopCause::StepLimit { max_steps: 3, .. })
        ));
        // A new interval starts the count again.
        g.next_output(2.0);
        assert_eq!(g.check(1.1, &stats(4, 0.1)), None);
        stop.request(crate::stop::SIGTERM);
        let cause = g.check(1.2, &stats(5, 0.1)).expect("stop");
        assert_eq!(cause, StopCause::Signal(crate::stop::SIGTERM));
        assert_eq!(cause.kind(), FailureKind::Interrupted);
        assert!(
            cause
                .reason(1.2)
                .starts_with("interrupted by SIGTERM at t = 1.2")
        );
    }
}

#[cfg(test)]
mod admissible {
    use super::*;

    /// A state whose node moved further than the scene allows stops the run (kind
    /// `unphysical`, nothing written); the state an inch short of it does not.
    #[test]
    fn a_state_past_the_scene_is_refused_as_unphysical() {
        let case = Case::load("cases/fast/flat-gravity.ron").unwrap();
        // The cell's diameter, 20 µm, plus its 0.5 µm above the substrate.
        let reach = scene_reach(&case);
        assert!((reach - 20.5).abs() < 1e-12, "{reach}");
        let model = build_model(&case, "flat-gravity", &case.solver).unwrap();
        let (_, mut y, _) = model.initial();
        assert!(observe_admissible(&model, 0.0, &y, reach).is_ok());
        // The first displacement unknown: 0.99 of the reach is a state, 1.01 is not.
        y[0] = 0.99 * reach;
        assert!(observe_admissible(&model, 1.0, &y, reach).is_ok());
        y[0] = 1.01 * reach;
        let Err(stop) = observe_admissible(&model, 1.0, &y, reach) else {
            panic!("accepted a node 1.01 × the reach away");
        };
        let Stop { kind, reason, .. } = stop.into_stop().unwrap();
        assert_eq!(kind, FailureKind::Unphysical);
        assert!(
            reason.starts_with("unphysical state at t = 1.000000e0 s"),
            "{reason}"
        );
        assert!(reason.contains("moved 2.0705e1 µm"), "{reason}");
        // On pillars the floor between them counts: 5 µm pillars below the tops.
        let pillars = Case::load("cases/pillars-push-pull.ron").unwrap();
        let floor_gap = scene_reach(&pillars) - 20.0;
        assert!(floor_gap > 5.0, "{floor_gap}");
    }
}
