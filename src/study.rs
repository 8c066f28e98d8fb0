//! `cellsim study`: the time-step sensitivity and work-precision study of one scene.
//!
//! The study reads as its algorithm:
//!
//! 1. **Reference**: IDA at a tight tolerance (`ref_rtol`, 1e-8 by default; if that run
//!    fails, 10× looser until one finishes, at most [`REF_ATTEMPTS`] tries — the rtol used
//!    is recorded). Its absolute tolerance is the case's, scaled by `ref_rtol / case rtol`.
//! 2. **BDF2 ladder**: fixed-step BDF2 at dt = `dt_max`, `dt_max`/2, … . A rung that fails
//!    before any rung has finished does not count: the ladder halves on until it has
//!    `rungs` rungs from the largest dt that converges down (at most
//!    [`MAX_LEADING_FAILURES`] failures first). With `dt_inertia` (default
//!    [`default_dt_inertia`]) the step of the fall (while the system has inertia) is capped
//!    at `dt_inertia` on the largest rung and halved along with dt, so every part of the
//!    solution is refined by the ladder. BDF2's
//!    Newton iteration is converged to `bdf2_rtol` (default 1e-8), far below its
//!    truncation error, so the error measured is the method's.
//! 3. **IDA ladder**: IDA at each of `rtols` (absolute tolerance scaled with rtol as for
//!    the reference).
//! 4. For every run: wall time, steps, Jacobian evaluations, LU factorizations and the
//!    relative error of each quantity of interest against the reference — the final
//!    values of uy_top, contact radius and both strain norms, and the max-in-time error
//!    of the displacement curve uy_top(t) over the output times (every run of a scene
//!    uses the same output times, so curves compare point-wise). Relative: |x − x_ref| /
//!    |x_ref|, and for the curve max_t |uy − uy_ref| / max_t |uy_ref|.
//! 5. The fitted BDF2 order (least-squares slope of log error against log dt of the
//!    max-in-time error of uy_top(t), the global error; final values of this dissipative
//!    model forget early errors, so their slopes are reported but not taken), the IDA
//!    slopes against rtol, the IDA-over-BDF2 speed-up at equal error (wall time of each
//!    ladder at [`TARGET_ERROR`] relative error of the final uy_top, interpolated log-log
//!    on each ladder, extrapolated from the two nearest runs when the ladder does not
//!    bracket it — and then said so), and a check of the reference against BDF2 at its
//!    smallest dt: their difference (on the uy_top curve) should match BDF2's own error
//!    estimated by Richardson extrapolation from its two smallest rungs.
//!
//! Outputs, in `DIR`: `runs/<label>/` (each run's normal outputs, [`crate::run::run`]),
//! `study.csv` (one row per run, appended and flushed as each run finishes, so an
//! interruption keeps what is done; a failed run is a row with its reason),
//! `study.json` (settings, reference, fits, speed-up, rows) and the figures
//! `work-precision.png` and `dt-sensitivity.png` ([`crate::output::study_plots`]).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::case::{self, Case};
use crate::dae::Stats;
use crate::model::observe::Observables;
use crate::output::read::parse_timeseries;
use crate::run::{self, FailureKind, Progress, RunError, RunOptions, RunSettings, Summary};
use crate::stop::StopFlag;

/// Relative error of the final uy_top at which the speed-up is measured.
pub const TARGET_ERROR: f64 = 1e-3;
/// The quantity BDF2's order is fitted on: the max-in-time error of the uy_top curve.
pub const ORDER_QUANTITY: Quantity = Quantity::UyTopCurve;
/// Tries of the reference, each 10× looser than the last.
pub const REF_ATTEMPTS: usize = 3;
/// Failed rungs tolerated at the top of the BDF2 ladder before giving up on it.
pub const MAX_LEADING_FAILURES: usize = 4;

/// A quantity of interest.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Final vertical displacement of the nucleus top p_t.
    UyTop,
    /// Final contact radius.
    ContactRadius,
    /// Final mean ‖E‖ over the nucleus.
    StrainNucleus,
    /// Final mean ‖E‖ over the cytoplasm.
    StrainCytoplasm,
    /// The displacement curve uy_top(t): max-in-time error.
    UyTopCurve,
}

impl Quantity {
    /// All quantities, in column order.
    pub const ALL: [Quantity; 5] = [
        Quantity::UyTop,
        Quantity::ContactRadius,
        Quantity::StrainNucleus,
        Quantity::StrainCytoplasm,
        Quantity::UyTopCurve,
    ];

    /// Column key (`err_<key>` in study.csv).
    pub fn key(self) -> &'static str {
        match self {
            Quantity::UyTop => "uy_top",
            Quantity::ContactRadius => "contact_radius",
            Quantity::StrainNucleus => "strain_nucleus",
            Quantity::StrainCytoplasm => "strain_cytoplasm",
            Quantity::UyTopCurve => "uy_top_curve",
        }
    }

    /// Human description for figures.
    pub fn title(self) -> &'static str {
        match self {
            Quantity::UyTop => "final uy(p_t)",
            Quantity::ContactRadius => "final contact radius",
            Quantity::StrainNucleus => "final mean |E| nucleus",
            Quantity::StrainCytoplasm => "final mean |E| cytoplasm",
            Quantity::UyTopCurve => "max over t of uy(p_t)(t)",
        }
    }

    fn final_value(self, o: &Observables) -> f64 {
        match self {
            Quantity::UyTop | Quantity::UyTopCurve => o.uy_top,
            Quantity::ContactRadius => o.contact_radius,
            Quantity::StrainNucleus => o.strain_nucleus,
            Quantity::StrainCytoplasm => o.strain_cytoplasm,
        }
    }
}

/// Which ladder a run belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// The reference (IDA at the tightest tolerance).
    Reference,
    /// The BDF2 dt ladder.
    Bdf2,
    /// The IDA rtol ladder.
    Ida,
}

impl Role {
    /// Name in study.csv.
    pub fn name(self) -> &'static str {
        match self {
            Role::Reference => "reference",
            Role::Bdf2 => "bdf2",
            Role::Ida => "ida",
        }
    }
}

/// Options of a study: its settings and how to run it.
#[derive(Clone)]
pub struct StudyOptions {
    /// Output directory.
    pub out: PathBuf,
    /// The ladders and tolerances (recorded in study.json).
    pub settings: StudySettings,
    /// Keep runs in `out/runs` that finished with the same settings.
    pub reuse: bool,
    /// Show a progress line during each run (on a terminal).
    pub progress: bool,
    /// Set to stop cleanly (Ctrl-C).
    pub interrupt: StopFlag,
}

/// Default largest BDF2 step: t_end / 100.
pub fn default_dt_max(case: &Case) -> f64 {
    case.phases.t_end / 100.0
}

/// Default BDF2 step of the fall on the largest rung: when the case switches inertia off
/// after `t_s` (`OffAfter(t_s)`), `t_s / 16`, at most `dt_max` — sixteen steps resolve the
/// fall and landing, where a step sized for the slow phases (t_end / 100) fails on the
/// landing's contact however often it is halved. `None` otherwise (with inertia `On`
/// throughout, `dt` is the step of the whole run; with `Off` there is no fall).
pub fn default_dt_inertia(case: &Case, dt_max: f64) -> Option<f64> {
    match case.inertia.mode {
        case::InertiaMode::OffAfter(ts) if ts < case.phases.t_end => Some((ts / 16.0).min(dt_max)),
        _ => None,
    }
}

/// Default IDA rtol ladder.
pub const DEFAULT_RTOLS: [f64; 6] = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7];
/// Default number of BDF2 rungs: six from t_end/100 reach the rungs where the pillar
/// scenes' contact onsets are resolved and the order is visible.
pub const DEFAULT_RUNGS: usize = 6;
/// Default reference rtol (IDA).
pub const DEFAULT_REF_RTOL: f64 = 1e-8;
/// Default rtol of BDF2's Newton test: far below its truncation error.
pub const DEFAULT_BDF2_RTOL: f64 = 1e-8;

/// One run of the study: a row of study.csv.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct StudyRow {
    /// Directory name under `runs/`.
    pub label: String,
    /// Ladder.
    pub role: Role,
    /// BDF2 step [s] (BDF2 only).
    pub dt: Option<f64>,
    /// BDF2 step of the fall [s] (BDF2 with a capped fall only).
    pub dt_inertia: Option<f64>,
    /// rtol (IDA: error test; BDF2: Newton test).
    pub rtol: f64,
    /// atol [µm].
    pub atol: f64,
    /// Whether the run reached the end time.
    pub finished: bool,
    /// Why not.
    pub failure: Option<String>,
    /// What kind of stop that was (absent in study files written before it was recorded).
    #[serde(default)]
    pub failure_kind: Option<FailureKind>,
    /// Whether it was reused from an earlier study.
    pub reused: bool,
    /// Wall-clock seconds of the integration.
    pub wall_seconds: f64,
    /// Integrator statistics.
    pub stats: Stats,
    /// Last output values.
    pub final_values: Option<Observables>,
    /// Relative errors against the reference, per quantity (None: not computable).
    pub errors: Vec<(Quantity, Option<f64>)>,
}

impl StudyRow {
    /// The error of `q`, if computed.
    pub fn error(&self, q: Quantity) -> Option<f64> {
        self.errors
            .iter()
            .find(|(k, _)| *k == q)
            .and_then(|(_, e)| *e)
    }

    /// The ladder's abscissa: dt for BDF2, rtol for IDA.
    pub fn knob(&self) -> f64 {
        match self.role {
            Role::Bdf2 => self.dt.unwrap_or(f64::NAN),
            _ => self.rtol,
        }
    }
}

/// A least-squares line through (ln x, ln y).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LogLogFit {
    /// Slope (the order).
    pub slope: f64,
    /// ln y at ln x = 0.
    pub intercept: f64,
    /// Points used.
    pub n: usize,
}

impl LogLogFit {
    /// y on the fitted line at x.
    pub fn eval(&self, x: f64) -> f64 {
        (self.intercept + self.slope * x.ln()).exp()
    }
}

/// Least-squares fit of ln y = a + p ln x over the points with x, y > 0 and finite;
/// None with fewer than two such points or all x equal.
pub fn fit_loglog(points: &[(f64, f64)]) -> Option<LogLogFit> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| x.is_finite() && y.is_finite() && *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = pts.len();
    if n < 2 {
        return None;
    }
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n as f64;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n as f64;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if !(sxx > 0.0) {
        return None;
    }
    let slope = sxy / sxx;
    Some(LogLogFit {
        slope,
        intercept: my - slope * mx,
        n,
    })
}

/// y at `x` on the piecewise log-log line through `points` (taken in order of x; points
/// with non-positive or non-finite coordinates dropped), interpolated between the two
/// points that bracket x. Outside the points' span, extrapolated along the least-squares
/// log-log line through all of them (steadier than the two end points when the data are
/// noisy, as wall times are). Returns (y, extrapolated); None with fewer than two usable
/// points.
pub fn interp_loglog(points: &[(f64, f64)], x: f64) -> Option<(f64, bool)> {
    let mut pts: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(a, b)| a.is_finite() && b.is_finite() && *a > 0.0 && *b > 0.0)
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    pts.dedup_by(|a, b| a.0 == b.0);
    if pts.len() < 2 || !(x > 0.0) {
        return None;
    }
    match pts.windows(2).find(|w| w[0].0 <= x && x <= w[1].0) {
        Some(w) => {
            let (x0, y0) = (w[0].0.ln(), w[0].1.ln());
            let (x1, y1) = (w[1].0.ln(), w[1].1.ln());
            let s = (x.ln() - x0) / (x1 - x0);
            Some(((y0 + s * (y1 - y0)).exp(), false))
        }
        None => fit_loglog(&pts).map(|f| (f.eval(x), true)),
    }
}

/// Relative errors of `run` (its output rows) against the reference's rows.
pub fn errors_against(
    quantities: &[Quantity],
    run: &[Observables],
    reference: &[Observables],
    finished: bool,
) -> Vec<(Quantity, Option<f64>)> {
    let rel = |a: f64, b: f64| {
        if b != 0.0 {
            (a - b).abs() / b.abs()
        } else {
            (a - b).abs()
        }
    };
    quantities
        .iter()
        .map(|&q| {
            if !finished || run.is_empty() || reference.is_empty() {
                return (q, None);
            }
            let e = match q {
                Quantity::UyTopCurve => curve_error(run, reference),
                _ => {
                    let (a, b) = (run[run.len() - 1], reference[reference.len() - 1]);
                    let same_t = (a.t - b.t).abs() <= 1e-9 * b.t.abs().max(1.0);
                    same_t.then(|| rel(q.final_value(&a), q.final_value(&b)))
                }
            };
            (q, e)
        })
        .collect()
}

/// max_t |uy − uy_ref| / max_t |uy_ref| over the common output times (None if the rows do
/// not share their times).
fn curve_error(run: &[Observables], reference: &[Observables]) -> Option<f64> {
    if run.len() != reference.len() {
        return None;
    }
    let mut diff: f64 = 0.0;
    let mut scale: f64 = 0.0;
    for (a, b) in run.iter().zip(reference) {
        if (a.t - b.t).abs() > 1e-9 * b.t.abs().max(1.0) {
            return None;
        }
        diff = diff.max((a.uy_top - b.uy_top).abs());
        scale = scale.max(b.uy_top.abs());
    }
    Some(if scale > 0.0 { diff / scale } else { diff })
}

/// Why a study could not run or finish.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The reference did not finish at any tolerance tried.
    #[error("reference: {0}")]
    Reference(String),
    /// The study was interrupted before the reference finished.
    #[error("interrupted before the reference finished")]
    Interrupted,
    /// A run could not be set up (mesh, model, files).
    #[error(transparent)]
    Run(#[from] RunError),
    /// A study file could not be written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// File.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// A figure could not be drawn.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> StudyError + '_ {
    move |source| StudyError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// The settings of the case scaled to `rtol`: atol keeps the case's atol/rtol ratio.
fn scaled_settings(case: &Case, integrator: case::Integrator, rtol: f64) -> RunSettings {
    let mut s = RunSettings::from_case(case);
    s.integrator = integrator;
    s.atol = case.solver.atol * rtol / case.solver.rtol;
    s.rtol = rtol;
    s
}

/// A number as it appears in a label: shortest exact decimal, or 1e-8 style for
/// tolerances.
fn fmt_num(x: f64) -> String {
    format!("{x}")
}

fn fmt_rtol(x: f64) -> String {
    format!("{x:e}")
}

/// A run's outcome, as read back from its files.
struct Outcome {
    row: StudyRow,
    series: Vec<Observables>,
}

/// Runs (or reuses) one run of the study.
fn one_run(
    case: &Case,
    file: &str,
    opts: &StudyOptions,
    role: Role,
    label: String,
    settings: RunSettings,
) -> Result<Outcome, StudyError> {
    let dir = opts.out.join("runs").join(&label);
    let mut summary: Option<Summary> = None;
    let mut reused = false;
    if opts.reuse {
        if let Some(s) = reusable(&dir, &settings) {
            summary = Some(s);
            reused = true;
        }
    }
    if summary.is_none() {
        let progress = match Progress::for_stderr(case, !opts.progress) {
            Progress::Bar(bar) => {
                bar.set_prefix(label.clone());
                Progress::Bar(bar)
            }
            Progress::Lines { every, .. } => Progress::Lines {
                label: format!("study: {label}"),
                every,
            },
            Progress::Hidden => Progress::Hidden,
        };
        let ropts = RunOptions {
            out: dir.clone(),
            settings: settings.clone(),
            progress,
            interrupt: opts.interrupt.clone(),
            snapshots: Default::default(),
        };
        summary = Some(match run::run(case, file, &ropts) {
            Ok(s) => s,
            Err(RunError::Integration { summary, .. }) => *summary,
            Err(e @ (RunError::Mesh { .. } | RunError::Scene(_) | RunError::Io { .. })) => {
                return Err(e.into());
            }
            Err(e) => {
                // The integrator could not be set up with these settings: a failed row.
                return Ok(Outcome {
                    row: StudyRow {
                        label,
                        role,
                        dt: (settings.integrator == case::Integrator::Bdf2).then_some(settings.dt),
                        dt_inertia: settings.dt_inertia,
                        rtol: settings.rtol,
                        atol: settings.atol,
                        finished: false,
                        failure: Some(e.to_string()),
                        failure_kind: Some(FailureKind::Integration),
                        reused: false,
                        wall_seconds: 0.0,
                        stats: Stats::default(),
                        final_values: None,
                        errors: Vec::new(),
                    },
                    series: Vec::new(),
                });
            }
        });
    }
    let summary = summary.unwrap_or_else(|| unreachable!("set above"));
    let csv = dir.join("timeseries.csv");
    let text = std::fs::read_to_string(&csv).map_err(io_err(&csv))?;
    let (series, _) = parse_timeseries(&csv, &text)?;
    let bdf2 = settings.integrator == case::Integrator::Bdf2;
    Ok(Outcome {
        row: StudyRow {
            label,
            role,
            dt: bdf2.then_some(settings.dt),
            dt_inertia: if bdf2 { settings.dt_inertia } else { None },
            rtol: settings.rtol,
            atol: settings.atol,
            finished: summary.finished,
            failure_kind: summary.failure.as_ref().map(|f| f.kind),
            failure: summary.failure.map(|f| f.reason),
            reused,
            wall_seconds: summary.wall_seconds,
            stats: summary.stats,
            final_values: summary.final_values,
            errors: Vec::new(),
        },
        series,
    })
}

/// The summary of a finished run in `dir` made with `settings` (the wall budget aside).
fn reusable(dir: &Path, settings: &RunSettings) -> Option<Summary> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let s: Summary = serde_json::from_str(&text).ok()?;
    let mut a = s.settings.clone();
    let mut b = settings.clone();
    a.max_wall_seconds = None;
    b.max_wall_seconds = None;
    // Compared as read back from JSON: the parser may round a float differently in the
    // last bit, so `b` takes the same path.
    let b: RunSettings = serde_json::from_str(&serde_json::to_string(&b).ok()?).ok()?;
    (s.finished && a == b && dir.join("timeseries.csv").exists()).then_some(s)
}

/// study.csv, appended and flushed row by row.
struct CsvWriter {
    path: PathBuf,
    w: BufWriter<File>,
    quantities: Vec<Quantity>,
}

impl CsvWriter {
    fn create(path: PathBuf, quantities: &[Quantity]) -> Result<Self, StudyError> {
        let mut w = BufWriter::new(File::create(&path).map_err(io_err(&path))?);
        let mut header = String::from(
            "label,integrator,dt,dt_inertia,rtol,atol,finished,wall_seconds,steps,residual_evals,jacobian_evals,lu_factorizations,newton_iters,newton_failures,error_test_failures,t_last,uy_top,contact_radius,strain_nucleus,strain_cytoplasm",
        );
        for q in quantities {
            header.push_str(&format!(",err_{}", q.key()));
        }
        header.push_str(",reused,failure");
        writeln!(w, "{header}")
            .and_then(|_| w.flush())
            .map_err(io_err(&path))?;
        Ok(Self {
            path,
            w,
            quantities: quantities.to_vec(),
        })
    }

    fn write(&mut self, r: &StudyRow) -> Result<(), StudyError> {
        let opt = |x: Option<f64>| x.map(|v| format!("{v}")).unwrap_or_default();
        let f = r.final_values;
        let s = &r.stats;
        let mut line = format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.label,
            r.role.name(),
            opt(r.dt),
            opt(r.dt_inertia),
            r.rtol,
            r.atol,
            r.finished,
            r.wall_seconds,
            s.steps,
            s.residual_evals,
            s.jacobian_evals,
            s.lu_factorizations,
            s.newton_iters,
            s.newton_failures,
            s.error_test_failures,
            opt(f.map(|o| o.t)),
            opt(f.map(|o| o.uy_top)),
            opt(f.map(|o| o.contact_radius)),
            opt(f.map(|o| o.strain_nucleus)),
            opt(f.map(|o| o.strain_cytoplasm)),
        );
        for q in &self.quantities {
            line.push(',');
            line.push_str(&opt(r.error(*q)));
        }
        let failure = r.failure.clone().unwrap_or_default().replace('"', "\"\"");
        line.push_str(&format!(",{},\"{failure}\"", r.reused));
        writeln!(self.w, "{line}")
            .and_then(|_| self.w.flush())
            .map_err(io_err(&self.path))
    }
}

/// The reference's settings and outcome, as study.json records it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReferenceInfo {
    /// Run label.
    pub label: String,
    /// rtol used (the tightest that finished).
    pub rtol: f64,
    /// atol used [µm].
    pub atol: f64,
    /// Tolerances tried that failed, with the reason.
    pub failed_attempts: Vec<(f64, String)>,
    /// Wall seconds.
    pub wall_seconds: f64,
    /// Statistics.
    pub stats: Stats,
    /// Final values.
    pub final_values: Option<Observables>,
}

/// The reference checked against BDF2 at its smallest dt, on the uy_top curve.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReferenceCheck {
    /// The BDF2 run (smallest dt that finished).
    pub bdf2_label: String,
    /// Its dt [s].
    pub dt: f64,
    /// Max-in-time relative difference of the uy_top curves, BDF2 against the reference.
    pub rel_diff_curve: Option<f64>,
    /// BDF2's own error there by Richardson extrapolation from its two smallest rungs
    /// (dt and 2dt), with order 2: max_t |uy_dt − uy_2dt| / 3 / max_t |uy_ref|.
    pub richardson_curve: Option<f64>,
    /// rel_diff_curve / richardson_curve: ≈ 1 when the reference is well below BDF2's
    /// error and BDF2 is in its asymptotic range.
    pub ratio: Option<f64>,
    /// |uy_top(BDF2) − uy_top(ref)| / |uy_top(ref)| at the end.
    pub rel_diff_uy_top: f64,
}

/// The fitted BDF2 order: on the max-in-time error of the uy_top curve, the global error
/// of the solution. (Final values of a dissipative scene forget early errors, so their
/// error need not fall as dt^p; their slopes are in `per_quantity`.)
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct OrderFit {
    /// The quantity the order is fitted on.
    pub quantity: Quantity,
    /// dt of the rungs used [s], largest first.
    pub dt: Vec<f64>,
    /// Their relative errors.
    pub error: Vec<f64>,
    /// Orders between successive rungs, log2(e(dt) / e(dt/2)).
    pub local_orders: Vec<f64>,
    /// The same for the final uy_top.
    pub final_uy_top_local_orders: Vec<f64>,
    /// Fitted slope per quantity.
    pub per_quantity: Vec<(Quantity, Option<f64>)>,
}

/// The speed-up at equal error.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Speedup {
    /// Relative error of the final uy_top at which walls are compared.
    pub target_error: f64,
    /// BDF2's wall time there [s].
    pub bdf2_wall: Option<f64>,
    /// Whether BDF2's ladder had to be extrapolated.
    pub bdf2_extrapolated: bool,
    /// IDA's wall time there [s].
    pub ida_wall: Option<f64>,
    /// Whether IDA's ladder had to be extrapolated.
    pub ida_extrapolated: bool,
    /// The cheapest IDA run whose error is at or below the target: (label, wall [s]).
    /// A run that meets the target costs at least the interpolated wall, so BDF2's wall
    /// over this one bounds the speed-up from below without extrapolating IDA's ladder.
    pub ida_meeting_target: Option<(String, f64)>,
    /// BDF2's wall at the target over `ida_meeting_target`'s: a lower bound of the
    /// speed-up.
    pub ida_speedup_at_least: Option<f64>,
}

/// study.json.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct StudyReport {
    /// Case name.
    pub case: String,
    /// Case file.
    pub case_file: String,
    /// Output times of every run (count).
    pub output_times: usize,
    /// The reference.
    pub reference: ReferenceInfo,
    /// The reference against BDF2's smallest dt.
    pub reference_check: Option<ReferenceCheck>,
    /// Fitted BDF2 order: slope of log error against log dt of the uy_top curve's
    /// max-in-time error ([`ORDER_QUANTITY`]) over the rungs that finished.
    pub bdf2_order: Option<f64>,
    /// Details of the fit.
    pub bdf2_order_fit: OrderFit,
    /// IDA's slopes of log error against log rtol, per quantity.
    pub ida_rtol_slopes: Vec<(Quantity, Option<f64>)>,
    /// Ratio of BDF2's to IDA's wall time at [`TARGET_ERROR`] relative error of the
    /// final uy_top.
    pub ida_speedup: Option<f64>,
    /// How it was obtained.
    pub ida_speedup_detail: Speedup,
    /// Whether the study was interrupted (what is here is what was done).
    pub interrupted: bool,
    /// Study settings.
    pub settings: StudySettings,
    /// Every run, in the order run.
    pub runs: Vec<StudyRow>,
}

/// The ladder settings, as recorded in study.json.
/// The ladders and tolerances of a study, as recorded in study.json.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct StudySettings {
    /// Largest BDF2 step tried [s] (default [`default_dt_max`]).
    pub dt_max: f64,
    /// BDF2 rungs wanted from the largest dt that converges down.
    pub rungs: usize,
    /// IDA's rtol ladder.
    pub rtols: Vec<f64>,
    /// rtol of the reference (IDA) asked for.
    pub ref_rtol: f64,
    /// rtol of BDF2's Newton convergence test (atol scaled alike).
    pub bdf2_rtol: f64,
    /// BDF2's step during the fall on the largest rung, halved with dt [s] (default
    /// [`default_dt_inertia`]).
    pub dt_inertia: Option<f64>,
    /// Wall-clock budget of each run [s].
    pub max_wall: Option<f64>,
    /// Quantities reported in study.csv and the figures.
    pub quantities: Vec<Quantity>,
}

impl StudySettings {
    /// The defaults for `case`.
    pub fn defaults(case: &Case) -> Self {
        let dt_max = default_dt_max(case);
        Self {
            dt_max,
            rungs: DEFAULT_RUNGS,
            rtols: DEFAULT_RTOLS.to_vec(),
            ref_rtol: DEFAULT_REF_RTOL,
            bdf2_rtol: DEFAULT_BDF2_RTOL,
            dt_inertia: default_dt_inertia(case, dt_max),
            max_wall: None,
            quantities: Quantity::ALL.to_vec(),
        }
    }
}

fn progress_line(r: &StudyRow) {
    let err = |q| {
        r.error(q)
            .map(|e| format!("{e:.3e}"))
            .unwrap_or_else(|| "—".into())
    };
    if r.finished {
        eprintln!(
            "study: {:<22} {:>8.2} s wall {:>7} steps {:>6} jac   err uy_top {}  curve {}{}",
            r.label,
            r.wall_seconds,
            r.stats.steps,
            r.stats.jacobian_evals,
            err(Quantity::UyTop),
            err(Quantity::UyTopCurve),
            if r.reused { "  (reused)" } else { "" }
        );
    } else {
        eprintln!(
            "study: {:<22} FAILED after {:.2} s wall, {} steps, last output t = {}: {}",
            r.label,
            r.wall_seconds,
            r.stats.steps,
            r.final_values.map(|o| o.t).unwrap_or(0.0),
            r.failure.as_deref().unwrap_or("?")
        );
    }
}

/// Whether a failed run stopped for the wall budget or an interruption (not the method).
fn stopped_by_driver(r: &StudyRow) -> bool {
    r.failure_kind.is_some_and(FailureKind::is_external)
}

/// Runs the study; see the module documentation.
pub fn run_study(case: &Case, file: &str, opts: &StudyOptions) -> Result<StudyReport, StudyError> {
    std::fs::create_dir_all(&opts.out).map_err(io_err(&opts.out))?;
    // Every error is computed internally (uy_top drives the fit and the speed-up); the
    // CSV and figures show the quantities asked for.
    let all = Quantity::ALL.to_vec();
    let set = &opts.settings;
    let mut csv = CsvWriter::create(opts.out.join("study.csv"), &set.quantities)?;
    let interrupted = || opts.interrupt.is_set();

    // 1. The reference.
    let mut failed_attempts = Vec::new();
    let mut reference: Option<Outcome> = None;
    let mut rtol = set.ref_rtol;
    for _ in 0..REF_ATTEMPTS {
        let settings = {
            let mut s = scaled_settings(case, case::Integrator::Ida, rtol);
            s.max_wall_seconds = set.max_wall;
            s
        };
        let label = format!("ref-ida-rtol{}", fmt_rtol(rtol));
        let mut o = one_run(case, file, opts, Role::Reference, label, settings)?;
        if o.row.finished {
            o.row.errors = errors_against(&all, &o.series, &o.series, true);
            progress_line(&o.row);
            csv.write(&o.row)?;
            reference = Some(o);
            break;
        }
        progress_line(&o.row);
        csv.write(&o.row)?;
        if interrupted() {
            return Err(StudyError::Interrupted);
        }
        failed_attempts.push((rtol, o.row.failure.clone().unwrap_or_default()));
        rtol *= 10.0;
    }
    let Some(reference) = reference else {
        return Err(StudyError::Reference(format!(
            "IDA did not finish at rtol {}: {}",
            failed_attempts
                .iter()
                .map(|a| fmt_rtol(a.0))
                .collect::<Vec<_>>()
                .join(", "),
            failed_attempts
                .last()
                .map(|a| a.1.clone())
                .unwrap_or_default()
        )));
    };
    let ref_series = reference.series.clone();
    let mut rows: Vec<StudyRow> = vec![reference.row.clone()];
    let mut series: Vec<Vec<Observables>> = vec![reference.series.clone()];

    let mut record = |mut o: Outcome,
                      rows: &mut Vec<StudyRow>,
                      series: &mut Vec<Vec<Observables>>|
     -> Result<StudyRow, StudyError> {
        o.row.errors = errors_against(&all, &o.series, &ref_series, o.row.finished);
        progress_line(&o.row);
        csv.write(&o.row)?;
        rows.push(o.row.clone());
        series.push(o.series);
        Ok(o.row)
    };

    // 2. The BDF2 ladder, from the largest dt that converges down.
    let mut dt = set.dt_max;
    let mut dt_inertia = set.dt_inertia;
    let mut counted = 0;
    let mut leading_failures = 0;
    while counted < set.rungs && !interrupted() {
        let mut settings = scaled_settings(case, case::Integrator::Bdf2, set.bdf2_rtol);
        settings.dt = dt;
        settings.dt_inertia = dt_inertia;
        settings.max_wall_seconds = set.max_wall;
        let label = format!("bdf2-dt{}", fmt_num(dt));
        let o = one_run(case, file, opts, Role::Bdf2, label, settings)?;
        let row = record(o, &mut rows, &mut series)?;
        if row.finished || counted > 0 {
            counted += 1;
        } else {
            leading_failures += 1;
            if leading_failures >= MAX_LEADING_FAILURES {
                eprintln!(
                    "study: BDF2 failed on the {MAX_LEADING_FAILURES} largest rungs; giving up on the BDF2 ladder (try a smaller --dt-max or --dt-inertia)"
                );
                break;
            }
        }
        if !row.finished && stopped_by_driver(&row) {
            // Smaller steps would cost more: the remaining rungs cannot fit either.
            eprintln!(
                "study: {} stopped by the wall budget or an interruption; the smaller rungs are skipped",
                row.label
            );
            break;
        }
        dt /= 2.0;
        dt_inertia = dt_inertia.map(|h| h / 2.0);
    }

    // 3. The IDA ladder.
    for &r in &set.rtols {
        if interrupted() {
            break;
        }
        let mut settings = scaled_settings(case, case::Integrator::Ida, r);
        settings.max_wall_seconds = set.max_wall;
        let label = format!("ida-rtol{}", fmt_rtol(r));
        let o = one_run(case, file, opts, Role::Ida, label, settings)?;
        record(o, &mut rows, &mut series)?;
    }
    drop(csv);

    // 4. Fits, speed-up, reference check.
    let report = analyse(
        case,
        file,
        opts,
        ReferenceInfo {
            label: reference.row.label.clone(),
            rtol: reference.row.rtol,
            atol: reference.row.atol,
            failed_attempts,
            wall_seconds: reference.row.wall_seconds,
            stats: reference.row.stats.clone(),
            final_values: reference.row.final_values,
        },
        &rows,
        &series,
        interrupted(),
    );
    let json = opts.out.join("study.json");
    let text = serde_json::to_string_pretty(&report).map_err(|e| StudyError::Io {
        path: json.display().to_string(),
        source: std::io::Error::other(e),
    })?;
    std::fs::write(&json, text).map_err(io_err(&json))?;
    crate::output::study_plots::plot_study(&report, &opts.out)?;
    Ok(report)
}

/// The ladder points (knob, error of q) of the finished runs of one role.
pub fn ladder_points(rows: &[StudyRow], role: Role, q: Quantity) -> Vec<(f64, f64)> {
    rows.iter()
        .filter(|r| r.role == role && r.finished)
        .filter_map(|r| r.error(q).map(|e| (r.knob(), e)))
        .collect()
}

/// The work-precision points (error of q, wall seconds) of the finished runs of one role.
pub fn work_points(rows: &[StudyRow], role: Role, q: Quantity) -> Vec<(f64, f64)> {
    rows.iter()
        .filter(|r| r.role == role && r.finished)
        .filter_map(|r| r.error(q).map(|e| (e, r.wall_seconds)))
        .collect()
}

/// Wall time at relative error `target` on a ladder's (error, wall) points, see
/// [`interp_loglog`]; an extrapolation is refused (None) when the ladder's fit does not
/// have cost rising as error falls (the error is not converging along the ladder).
pub fn wall_at(points: &[(f64, f64)], target: f64) -> Option<(f64, bool)> {
    let w = interp_loglog(points, target)?;
    if w.1 && !fit_loglog(points).is_some_and(|f| f.slope < 0.0) {
        return None;
    }
    Some(w)
}

#[allow(clippy::too_many_arguments)]
fn analyse(
    case: &Case,
    file: &str,
    opts: &StudyOptions,
    reference: ReferenceInfo,
    rows: &[StudyRow],
    series: &[Vec<Observables>],
    interrupted: bool,
) -> StudyReport {
    let q0 = Quantity::UyTop;
    let local = |q: Quantity| {
        let mut pts = ladder_points(rows, Role::Bdf2, q);
        pts.sort_by(|a, b| b.0.total_cmp(&a.0));
        let orders = pts
            .windows(2)
            .map(|w| (w[0].1 / w[1].1).ln() / (w[0].0 / w[1].0).ln())
            .collect::<Vec<f64>>();
        (pts, orders)
    };
    let (sorted, local_orders) = local(ORDER_QUANTITY);
    let order = fit_loglog(&sorted).map(|f| f.slope);
    let per_q = |role| {
        Quantity::ALL
            .iter()
            .map(|&q| {
                (
                    q,
                    fit_loglog(&ladder_points(rows, role, q)).map(|f| f.slope),
                )
            })
            .collect::<Vec<_>>()
    };

    let bdf2_w = wall_at(&work_points(rows, Role::Bdf2, q0), TARGET_ERROR);
    let ida_w = wall_at(&work_points(rows, Role::Ida, q0), TARGET_ERROR);
    let speedup = match (bdf2_w, ida_w) {
        (Some((b, _)), Some((i, _))) if i > 0.0 => Some(b / i),
        _ => None,
    };
    let ida_meeting_target = rows
        .iter()
        .filter(|r| r.role == Role::Ida && r.finished)
        .filter(|r| r.error(q0).is_some_and(|e| e <= TARGET_ERROR))
        .min_by(|a, b| a.wall_seconds.total_cmp(&b.wall_seconds))
        .map(|r| (r.label.clone(), r.wall_seconds));
    let speedup_at_least = match (bdf2_w, &ida_meeting_target) {
        (Some((b, _)), Some((_, i))) if *i > 0.0 => Some(b / i),
        _ => None,
    };

    // The reference against BDF2's two smallest finished rungs.
    let bdf2_runs: Vec<(usize, &StudyRow)> = {
        let mut v: Vec<(usize, &StudyRow)> = rows
            .iter()
            .enumerate()
            .filter(|(_, r)| r.role == Role::Bdf2 && r.finished)
            .collect();
        v.sort_by(|a, b| a.1.knob().total_cmp(&b.1.knob()));
        v
    };
    let reference_check = bdf2_runs.first().map(|&(k, r)| {
        let uy = |r: &StudyRow| r.final_values.map(|o| o.uy_top).unwrap_or(f64::NAN);
        let uy_ref = reference.final_values.map(|o| o.uy_top).unwrap_or(f64::NAN);
        let scale = series[0].iter().fold(0.0_f64, |m, o| m.max(o.uy_top.abs()));
        let richardson = bdf2_runs.get(1).and_then(|&(k2, r2)| {
            let halved = (r2.knob() / r.knob() - 2.0).abs() < 1e-9;
            let d = series[k]
                .iter()
                .zip(&series[k2])
                .fold(0.0_f64, |m, (a, b)| m.max((a.uy_top - b.uy_top).abs()));
            (halved && series[k].len() == series[k2].len() && scale > 0.0).then(|| d / 3.0 / scale)
        });
        let rel_curve = curve_error(&series[k], &series[0]);
        ReferenceCheck {
            bdf2_label: r.label.clone(),
            dt: r.knob(),
            rel_diff_curve: rel_curve,
            richardson_curve: richardson,
            ratio: match (rel_curve, richardson) {
                (Some(a), Some(b)) if b > 0.0 => Some(a / b),
                _ => None,
            },
            rel_diff_uy_top: (uy(r) - uy_ref).abs() / uy_ref.abs(),
        }
    });

    StudyReport {
        case: case.name.clone(),
        case_file: file.to_string(),
        output_times: series.first().map_or(0, |s| s.len()),
        reference,
        reference_check,
        bdf2_order: order,
        bdf2_order_fit: OrderFit {
            quantity: ORDER_QUANTITY,
            dt: sorted.iter().map(|p| p.0).collect(),
            error: sorted.iter().map(|p| p.1).collect(),
            local_orders,
            final_uy_top_local_orders: local(q0).1,
            per_quantity: per_q(Role::Bdf2),
        },
        ida_rtol_slopes: per_q(Role::Ida),
        ida_speedup: speedup,
        ida_speedup_detail: Speedup {
            target_error: TARGET_ERROR,
            bdf2_wall: bdf2_w.map(|w| w.0),
            bdf2_extrapolated: bdf2_w.is_some_and(|w| w.1),
            ida_wall: ida_w.map(|w| w.0),
            ida_extrapolated: ida_w.is_some_and(|w| w.1),
            ida_meeting_target,
            ida_speedup_at_least: speedup_at_least,
        },
        interrupted,
        settings: opts.settings.clone(),
        runs: rows.to_vec(),
    }
}

/// The study's result as printed at the end: reference, table of runs, order, speed-up.
pub fn summary_text(r: &StudyReport) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let e = |x: Option<f64>| x.map(|v| format!("{v:.3e}")).unwrap_or_else(|| "—".into());
    let _ = writeln!(
        s,
        "reference: IDA rtol {:e}, atol {:.3e} µm, {:.1} s wall, {} steps{}",
        r.reference.rtol,
        r.reference.atol,
        r.reference.wall_seconds,
        r.reference.stats.steps,
        if r.reference.failed_attempts.is_empty() {
            String::new()
        } else {
            format!(
                " (tighter tolerances failed: {})",
                r.reference
                    .failed_attempts
                    .iter()
                    .map(|a| format!("{:e}", a.0))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }
    );
    let _ = writeln!(
        s,
        "{:<22} {:>9} {:>8} {:>6} {:>6} {:>10} {:>10} {:>10}",
        "run", "wall s", "steps", "jac", "LU", "err uy_top", "err cr", "err curve"
    );
    for row in &r.runs {
        if row.role == Role::Reference {
            continue;
        }
        let _ = writeln!(
            s,
            "{:<22} {:>9.2} {:>8} {:>6} {:>6} {:>10} {:>10} {:>10}{}",
            row.label,
            row.wall_seconds,
            row.stats.steps,
            row.stats.jacobian_evals,
            row.stats.lu_factorizations,
            e(row.error(Quantity::UyTop)),
            e(row.error(Quantity::ContactRadius)),
            e(row.error(Quantity::UyTopCurve)),
            match &row.failure {
                Some(f) if !row.finished => format!("  FAILED: {f}"),
                _ => String::new(),
            }
        );
    }
    let f = &r.bdf2_order_fit;
    let round = |v: &[f64]| {
        v.iter()
            .map(|p| format!("{p:.2}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let _ = writeln!(
        s,
        "bdf2_order (max-in-time error of uy_top(t)): {} over dt {:?}; local orders [{}] (final uy_top: [{}])",
        r.bdf2_order
            .map(|v| format!("{v:.2}"))
            .unwrap_or_else(|| "—".into()),
        f.dt,
        round(&f.local_orders),
        round(&f.final_uy_top_local_orders)
    );
    let d = &r.ida_speedup_detail;
    let how = |x: bool| if x { "extrapolated" } else { "interpolated" };
    let _ = writeln!(
        s,
        "ida_speedup at {:e} relative error of the final uy_top: {} (BDF2 {} s, {}; IDA {} s, {})",
        d.target_error,
        r.ida_speedup
            .map(|v| format!("{v:.2}"))
            .unwrap_or_else(|| "—".into()),
        e(d.bdf2_wall),
        how(d.bdf2_extrapolated),
        e(d.ida_wall),
        how(d.ida_extrapolated)
    );
    if let (Some(v), Some((label, w))) = (d.ida_speedup_at_least, &d.ida_meeting_target) {
        let _ = writeln!(
            s,
            "ida_speedup at least {v:.2}: BDF2's wall at the target over {label}'s ({w:.2} s), the cheapest IDA run within it"
        );
    }
    if let Some(c) = &r.reference_check {
        let _ = writeln!(
            s,
            "reference check: {} differs from the reference by {} (max over t of uy_top, relative); BDF2's own error there (Richardson, dt and 2dt) {}; ratio {}",
            c.bdf2_label,
            e(c.rel_diff_curve),
            e(c.richardson_curve),
            c.ratio
                .map(|v| format!("{v:.2}"))
                .unwrap_or_else(|| "—".into())
        );
    }
    if r.interrupted {
        let _ = writeln!(s, "interrupted: the study holds the runs done so far");
    }
    s
}
