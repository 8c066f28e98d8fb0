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
//! `work-precision.png` and `dt-sensitivity.png` ([`plots`]).
//!
//! Layout: this module is the driver; [`analysis`] the pure functions (fits,
//! interpolation, errors against the reference); [`report`] the types of the study's rows
//! and report, `study.csv` and the text summary; [`plots`] its figures.

pub mod analysis;
pub mod plots;
pub mod report;

use std::path::{Path, PathBuf};

use crate::case::{self, Case};
use crate::dae::Stats;
use crate::run::{self, Progress, RunError, RunOptions};
use crate::run_files::Observables;
use crate::run_files::read::parse_timeseries;
use crate::run_files::{FailureKind, SettingsUsed, Summary};
use crate::solver::{Limits, Settings};
use crate::stop::StopFlag;

use analysis::analyse;
pub use analysis::{
    CURVE_ERRORS, LogLogFit, errors_against, fit_loglog, interp_loglog, ladder_points,
    speedup_curve, wall_at, work_points,
};
use report::{CsvWriter, fmt_num, fmt_rtol, fmt_sci};
pub use report::{
    OrderFit, Quantity, ReferenceCheck, ReferenceInfo, Role, Speedup, SpeedupAt, StudyReport,
    StudyRow, StudySettings, summary_text,
};

/// Relative error of the final uy_top at which the speed-up is measured.
pub const TARGET_ERROR: f64 = 1e-3;
/// The quantity BDF2's order is fitted on: the max-in-time error of the uy_top curve.
pub const ORDER_QUANTITY: Quantity = Quantity::UyTopCurve;
/// Tries of the reference, each 10× looser than the last.
pub const REF_ATTEMPTS: usize = 3;
/// Failed rungs tolerated at the top of the BDF2 ladder before giving up on it.
pub const MAX_LEADING_FAILURES: usize = 4;

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
    /// A run's file could not be read back.
    #[error(transparent)]
    Read(#[from] crate::run_files::ReadError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Output(#[from] crate::render::OutputError),
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> StudyError + '_ {
    move |source| StudyError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// The settings of the case scaled to `rtol`: atol keeps the case's atol/rtol ratio.
fn scaled_settings(case: &Case, integrator: case::Integrator, rtol: f64) -> Settings {
    let mut s = case.solver.clone();
    s.integrator = integrator;
    s.atol = case.solver.atol * rtol / case.solver.rtol;
    s.rtol = rtol;
    s
}

/// What every run of a study shares: the case, its file and the study's options.
#[derive(Clone, Copy)]
struct Study<'a> {
    case: &'a Case,
    file: &'a str,
    opts: &'a StudyOptions,
}

impl Study<'_> {
    /// The case's settings for `integrator` scaled to `rtol` ([`scaled_settings`]), with
    /// the study's wall budget per run.
    fn settings(&self, integrator: case::Integrator, rtol: f64) -> SettingsUsed {
        SettingsUsed {
            solver: scaled_settings(self.case, integrator, rtol),
            limits: Limits {
                dt_inertia: None,
                max_wall_seconds: self.opts.settings.max_wall,
            },
        }
    }
}

/// A run's outcome, as read back from its files.
struct Outcome {
    row: StudyRow,
    series: Vec<Observables>,
}

/// Runs (or reuses) one run of the study.
fn one_run(
    study: Study<'_>,
    role: Role,
    label: String,
    used: SettingsUsed,
) -> Result<Outcome, StudyError> {
    let Study { case, file, opts } = study;
    let dir = opts.out.join("runs").join(&label);
    let mut summary: Option<Summary> = None;
    let mut reused = false;
    if opts.reuse {
        if let Some(s) = reusable(&dir, &used) {
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
            settings: used.solver.clone(),
            limits: used.limits,
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
                let settings = &used.solver;
                return Ok(Outcome {
                    row: StudyRow {
                        label,
                        role,
                        dt: (settings.integrator == case::Integrator::Bdf2)
                            .then_some(settings.bdf2_dt),
                        dt_inertia: used.limits.dt_inertia,
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
    let (settings, limits) = (&used.solver, &used.limits);
    let csv = dir.join("timeseries.csv");
    let text = std::fs::read_to_string(&csv).map_err(io_err(&csv))?;
    let (series, _) = parse_timeseries(&csv, &text)?;
    let bdf2 = settings.integrator == case::Integrator::Bdf2;
    Ok(Outcome {
        row: StudyRow {
            label,
            role,
            dt: bdf2.then_some(settings.bdf2_dt),
            dt_inertia: if bdf2 { limits.dt_inertia } else { None },
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

/// The summary of a finished run in `dir` made with `used` (the wall budget aside, and
/// for BDF2 the Krylov option, which only IDA uses: a study of IDA with GMRES reuses the
/// BDF2 ladder of one without).
fn reusable(dir: &Path, used: &SettingsUsed) -> Option<Summary> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let s: Summary = serde_json::from_str(&text).ok()?;
    let mut a = s.settings.clone();
    let mut b = used.clone();
    a.limits.max_wall_seconds = None;
    b.limits.max_wall_seconds = None;
    if b.solver.integrator == case::Integrator::Bdf2 {
        a.solver.krylov = None;
        b.solver.krylov = None;
    }
    // Compared as read back from JSON: the parser may round a float differently in the
    // last bit, so `b` takes the same path.
    let b: SettingsUsed = serde_json::from_str(&serde_json::to_string(&b).ok()?).ok()?;
    (s.finished && a == b && dir.join("timeseries.csv").exists()).then_some(s)
}

fn progress_line(r: &StudyRow) {
    let err = |q| fmt_sci(r.error(q));
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
    let csv = CsvWriter::create(opts.out.join("study.csv"), &opts.settings.quantities)?;
    // 1. The reference.
    let study = Study { case, file, opts };
    let (mut runs, failed_attempts) = reference_run(study, csv)?;
    // 2. The BDF2 ladder, from the largest dt that converges down.
    bdf2_ladder(study, &mut runs)?;
    // 3. The IDA ladder.
    ida_ladder(study, &mut runs)?;
    let Runs {
        csv, rows, series, ..
    } = runs;
    drop(csv);

    // 4. Fits, speed-up, reference check.
    let reference = &rows[0];
    let report = analyse(
        case,
        file,
        opts,
        ReferenceInfo {
            label: reference.label.clone(),
            rtol: reference.rtol,
            atol: reference.atol,
            failed_attempts,
            wall_seconds: reference.wall_seconds,
            stats: reference.stats.clone(),
            final_values: reference.final_values,
        },
        &rows,
        &series,
        opts.interrupt.is_set(),
    );
    write_report(&report, &opts.out)?;
    plots::plot_study(&report, &opts.out)?;
    Ok(report)
}

/// The runs of a study so far, each written to study.csv as it comes.
struct Runs {
    csv: CsvWriter,
    /// The reference's output rows, which every run is compared with.
    reference: Vec<Observables>,
    /// The rows of the runs, the reference first, in the order run.
    rows: Vec<StudyRow>,
    /// The output rows of each run, in the same order.
    series: Vec<Vec<Observables>>,
}

impl Runs {
    /// Computes a run's errors against the reference, prints and writes its row, and keeps
    /// it; returns the row.
    fn record(&mut self, mut o: Outcome) -> Result<StudyRow, StudyError> {
        // Every error is computed internally (uy_top drives the fit and the speed-up); the
        // CSV and figures show the quantities asked for.
        o.row.errors = errors_against(&Quantity::ALL, &o.series, &self.reference, o.row.finished);
        progress_line(&o.row);
        self.csv.write(&o.row)?;
        self.rows.push(o.row.clone());
        self.series.push(o.series);
        Ok(o.row)
    }
}

/// Runs the reference: IDA at `ref_rtol`, 10× looser after each failure, at most
/// [`REF_ATTEMPTS`] tries. Returns the runs with it first, and the tolerances that failed
/// with why.
fn reference_run(
    study: Study<'_>,
    mut csv: CsvWriter,
) -> Result<(Runs, Vec<(f64, String)>), StudyError> {
    let opts = study.opts;
    let mut failed_attempts = Vec::new();
    let mut rtol = opts.settings.ref_rtol;
    for _ in 0..REF_ATTEMPTS {
        let settings = study.settings(case::Integrator::Ida, rtol);
        let label = format!("ref-ida-rtol{}", fmt_rtol(rtol));
        let mut o = one_run(study, Role::Reference, label, settings)?;
        if o.row.finished {
            o.row.errors = errors_against(&Quantity::ALL, &o.series, &o.series, true);
            progress_line(&o.row);
            csv.write(&o.row)?;
            let runs = Runs {
                csv,
                reference: o.series.clone(),
                rows: vec![o.row],
                series: vec![o.series],
            };
            return Ok((runs, failed_attempts));
        }
        progress_line(&o.row);
        csv.write(&o.row)?;
        if opts.interrupt.is_set() {
            return Err(StudyError::Interrupted);
        }
        failed_attempts.push((rtol, o.row.failure.clone().unwrap_or_default()));
        rtol *= 10.0;
    }
    Err(StudyError::Reference(format!(
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
    )))
}

/// Runs the BDF2 ladder: dt halved from `dt_max` until `rungs` rungs from the largest dt
/// that converges down (giving up after [`MAX_LEADING_FAILURES`] failures first).
fn bdf2_ladder(study: Study<'_>, runs: &mut Runs) -> Result<(), StudyError> {
    let (opts, set) = (study.opts, &study.opts.settings);
    let mut dt = set.dt_max;
    let mut dt_inertia = set.dt_inertia;
    let mut counted = 0;
    let mut leading_failures = 0;
    while counted < set.rungs && !opts.interrupt.is_set() {
        let mut settings = study.settings(case::Integrator::Bdf2, set.bdf2_rtol);
        settings.solver.bdf2_dt = dt;
        settings.limits.dt_inertia = dt_inertia;
        let label = format!("bdf2-dt{}", fmt_num(dt));
        let o = one_run(study, Role::Bdf2, label, settings)?;
        let row = runs.record(o)?;
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
    Ok(())
}

/// Runs the IDA ladder: IDA at each of `rtols`.
fn ida_ladder(study: Study<'_>, runs: &mut Runs) -> Result<(), StudyError> {
    for &r in &study.opts.settings.rtols {
        if study.opts.interrupt.is_set() {
            break;
        }
        let settings = study.settings(case::Integrator::Ida, r);
        let label = format!("ida-rtol{}", fmt_rtol(r));
        let o = one_run(study, Role::Ida, label, settings)?;
        runs.record(o)?;
    }
    Ok(())
}

/// Writes study.json.
fn write_report(report: &StudyReport, out: &Path) -> Result<(), StudyError> {
    let json = out.join("study.json");
    let text = serde_json::to_string_pretty(report).map_err(|e| StudyError::Io {
        path: json.display().to_string(),
        source: std::io::Error::other(e),
    })?;
    std::fs::write(&json, text).map_err(io_err(&json))
}
