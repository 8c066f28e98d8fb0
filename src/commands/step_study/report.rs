//! The study's records: what each run gave (a row of `study.csv`), the report written to
//! `study.json`, the CSV writer and the text summary.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::{
    DEFAULT_BDF2_RTOL, DEFAULT_REF_RTOL, DEFAULT_RTOLS, DEFAULT_RUNGS, StudyError,
    default_dt_inertia, default_dt_max, io_err,
};
use crate::case::Case;
use crate::dae::Stats;
use crate::run_files::FailureKind;
use crate::run_files::Observables;

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

    pub(super) fn final_value(self, o: &Observables) -> f64 {
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

/// One run of the study: a row of study.csv.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct StudyRow {
    /// Directory name under `runs/`.
    pub label: String,
    /// Ladder.
    pub role: Role,
    /// BDF2 step \[s\] (BDF2 only).
    pub dt: Option<f64>,
    /// BDF2 step of the fall \[s\] (BDF2 with a capped fall only).
    pub dt_inertia: Option<f64>,
    /// rtol (IDA: error test; BDF2: Newton test).
    pub rtol: f64,
    /// atol \[µm\].
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

/// A number as it appears in a label: shortest exact decimal, or 1e-8 style for
/// tolerances.
pub(super) fn fmt_num(x: f64) -> String {
    format!("{x}")
}

pub(super) fn fmt_rtol(x: f64) -> String {
    format!("{x:e}")
}

/// study.csv, appended and flushed row by row.
pub(super) struct CsvWriter {
    path: PathBuf,
    w: BufWriter<File>,
    quantities: Vec<Quantity>,
}

impl CsvWriter {
    pub(super) fn create(path: PathBuf, quantities: &[Quantity]) -> Result<Self, StudyError> {
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

    pub(super) fn write(&mut self, r: &StudyRow) -> Result<(), StudyError> {
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
    /// atol used \[µm\].
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
    /// Its dt \[s\].
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
    /// dt of the rungs used \[s\], largest first.
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
    /// BDF2's wall time there \[s\].
    pub bdf2_wall: Option<f64>,
    /// Whether BDF2's ladder had to be extrapolated.
    pub bdf2_extrapolated: bool,
    /// IDA's wall time there \[s\].
    pub ida_wall: Option<f64>,
    /// Whether IDA's ladder had to be extrapolated.
    pub ida_extrapolated: bool,
    /// The cheapest IDA run whose error is at or below the target: (label, wall \[s\]).
    /// A run that meets the target costs at least the interpolated wall, so BDF2's wall
    /// over this one bounds the speed-up from below without extrapolating IDA's ladder.
    pub ida_meeting_target: Option<(String, f64)>,
    /// BDF2's wall at the target over `ida_meeting_target`'s: a lower bound of the
    /// speed-up (only when BDF2's wall there is interpolated, not extrapolated).
    pub ida_speedup_at_least: Option<f64>,
    /// The cheapest BDF2 run whose error is at or below the target: (label, wall \[s\]).
    #[serde(default)]
    pub bdf2_meeting_target: Option<(String, f64)>,
    /// The cheapest meeting BDF2 run's wall over the cheapest meeting IDA run's: what the
    /// two ladders as run cost to meet the target. When both ladders' loosest runs are
    /// already far within it (the speed-up's interpolation then extrapolates both), this
    /// is the ratio that was measured.
    #[serde(default)]
    pub cheapest_runs_ratio: Option<f64>,
}

/// The speed-up at one error of the displacement curve (max over t of uy_top's relative
/// error, [`Quantity::UyTopCurve`]): each ladder's wall interpolated log–log at the error
/// (extrapolated at most a decade past its ends, see [`super::analysis::wall_at`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpeedupAt {
    /// The error \[relative\].
    pub error: f64,
    /// BDF2's wall there \[s\] and whether it was extrapolated.
    pub bdf2_wall: Option<(f64, bool)>,
    /// IDA's wall there \[s\] and whether it was extrapolated.
    pub ida_wall: Option<(f64, bool)>,
    /// BDF2's wall over IDA's.
    pub ratio: Option<f64>,
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
    /// max-in-time error ([`super::ORDER_QUANTITY`]) over the rungs that finished.
    pub bdf2_order: Option<f64>,
    /// Details of the fit.
    pub bdf2_order_fit: OrderFit,
    /// IDA's slopes of log error against log rtol, per quantity.
    pub ida_rtol_slopes: Vec<(Quantity, Option<f64>)>,
    /// Ratio of BDF2's to IDA's wall time at [`super::TARGET_ERROR`] relative error of the
    /// final uy_top.
    pub ida_speedup: Option<f64>,
    /// How it was obtained.
    pub ida_speedup_detail: Speedup,
    /// The speed-up on the displacement curve at the errors 1e-3 … 1e-7 (where both
    /// ladders reach): on a dissipative scene the final values forget the path, and both
    /// ladders' loosest runs may already be far within the target there, so the curve is
    /// where the integrators' accuracy shows.
    #[serde(default)]
    pub speedup_curve: Vec<SpeedupAt>,
    /// Whether the study was interrupted (what is here is what was done).
    pub interrupted: bool,
    /// Study settings.
    pub settings: StudySettings,
    /// Every run, in the order run.
    pub runs: Vec<StudyRow>,
}

/// The ladders and tolerances of a study, as recorded in study.json.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct StudySettings {
    /// Largest BDF2 step tried \[s\] (default [`default_dt_max`]).
    pub dt_max: f64,
    /// BDF2 rungs wanted from the largest dt that converges down.
    pub rungs: usize,
    /// IDA's rtol ladder.
    pub rtols: Vec<f64>,
    /// rtol of the reference (IDA) asked for.
    pub ref_rtol: f64,
    /// rtol of BDF2's Newton convergence test (atol scaled alike).
    pub bdf2_rtol: f64,
    /// BDF2's step during the fall on the largest rung, halved with dt \[s\] (default
    /// [`default_dt_inertia`]).
    pub dt_inertia: Option<f64>,
    /// Wall-clock budget of each run \[s\].
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

/// `x` with three decimals in exponent notation, or — when absent.
pub(super) fn fmt_sci(x: Option<f64>) -> String {
    x.map(|v| format!("{v:.3e}")).unwrap_or_else(|| "—".into())
}

/// `x` with two decimals, or — when absent.
fn two_decimals(x: Option<f64>) -> String {
    x.map(|v| format!("{v:.2}")).unwrap_or_else(|| "—".into())
}

/// The study's result as printed at the end: reference, table of runs, order, speed-up.
pub fn summary_text(r: &StudyReport) -> String {
    let mut s = String::new();
    write_reference(&mut s, &r.reference);
    write_runs(&mut s, &r.runs);
    write_order(&mut s, r);
    write_speedup(&mut s, r);
    write_curve_speedup(&mut s, &r.speedup_curve);
    if let Some(c) = &r.reference_check {
        let _ = writeln!(
            s,
            "reference check: {} differs from the reference by {} (max over t of uy_top, relative); BDF2's own error there (Richardson, dt and 2dt) {}; ratio {}",
            c.bdf2_label,
            fmt_sci(c.rel_diff_curve),
            fmt_sci(c.richardson_curve),
            two_decimals(c.ratio)
        );
    }
    if r.interrupted {
        let _ = writeln!(s, "interrupted: the study holds the runs done so far");
    }
    s
}

/// The summary's line of the reference: tolerances, cost, and the tolerances that failed.
fn write_reference(s: &mut String, reference: &ReferenceInfo) {
    let _ = writeln!(
        s,
        "reference: IDA rtol {:e}, atol {:.3e} µm, {:.1} s wall, {} steps{}",
        reference.rtol,
        reference.atol,
        reference.wall_seconds,
        reference.stats.steps,
        if reference.failed_attempts.is_empty() {
            String::new()
        } else {
            format!(
                " (tighter tolerances failed: {})",
                reference
                    .failed_attempts
                    .iter()
                    .map(|a| format!("{:e}", a.0))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }
    );
}

/// The summary's table of the ladders' runs: cost and errors, and why a run failed.
fn write_runs(s: &mut String, runs: &[StudyRow]) {
    let _ = writeln!(
        s,
        "{:<22} {:>9} {:>8} {:>6} {:>6} {:>10} {:>10} {:>10}",
        "run", "wall s", "steps", "jac", "LU", "err uy_top", "err cr", "err curve"
    );
    for row in runs {
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
            fmt_sci(row.error(Quantity::UyTop)),
            fmt_sci(row.error(Quantity::ContactRadius)),
            fmt_sci(row.error(Quantity::UyTopCurve)),
            match &row.failure {
                Some(f) if !row.finished => format!("  FAILED: {f}"),
                _ => String::new(),
            }
        );
    }
}

/// The summary's line of BDF2's fitted order and local orders.
fn write_order(s: &mut String, r: &StudyReport) {
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
        two_decimals(r.bdf2_order),
        f.dt,
        round(&f.local_orders),
        round(&f.final_uy_top_local_orders)
    );
}

/// The summary's lines of the speed-up at the target error of the final uy_top: the
/// interpolated one, its lower bound and the cheapest runs' ratio.
fn write_speedup(s: &mut String, r: &StudyReport) {
    let d = &r.ida_speedup_detail;
    let how = |x: bool| if x { "extrapolated" } else { "interpolated" };
    let _ = writeln!(
        s,
        "ida_speedup at {:e} relative error of the final uy_top: {} (BDF2 {} s, {}; IDA {} s, {})",
        d.target_error,
        two_decimals(r.ida_speedup),
        fmt_sci(d.bdf2_wall),
        how(d.bdf2_extrapolated),
        fmt_sci(d.ida_wall),
        how(d.ida_extrapolated)
    );
    if let (Some(v), Some((label, w))) = (d.ida_speedup_at_least, &d.ida_meeting_target) {
        let _ = writeln!(
            s,
            "ida_speedup at least {v:.2}: BDF2's wall at the target over {label}'s ({w:.2} s), the cheapest IDA run within it"
        );
    }
    if let (Some(v), Some((bl, bw)), Some((il, iw))) = (
        d.cheapest_runs_ratio,
        &d.bdf2_meeting_target,
        &d.ida_meeting_target,
    ) {
        let _ = writeln!(
            s,
            "cheapest runs within the target: {bl} ({bw:.2} s) over {il} ({iw:.2} s) = {v:.2}"
        );
    }
}

/// The summary's lines of the speed-up at each error of the uy_top curve.
fn write_curve_speedup(s: &mut String, curve: &[SpeedupAt]) {
    let at = |w: Option<(f64, bool)>| match w {
        Some((v, x)) => format!("{v:.2} s{}", if x { " (extrapolated)" } else { "" }),
        None => "—".into(),
    };
    for p in curve {
        let _ = writeln!(
            s,
            "speed-up at {:e} error of the uy_top curve: {} (BDF2 {}, IDA {})",
            p.error,
            two_decimals(p.ratio),
            at(p.bdf2_wall),
            at(p.ida_wall)
        );
    }
}
