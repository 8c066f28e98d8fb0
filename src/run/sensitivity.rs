//! `cellsim sensitivity`: the derivatives of a scene's measures with respect to case
//! parameters, integrated by IDAS with the solution ([`crate::dae::sensitivity`]): the
//! state's sensitivities `∂y/∂p` exactly (to the integrator's tolerance), a measure's
//! `∂m/∂p = (m(y + hp s) − m(y − hp s)) / 2hp` along them (`h` = 1e-4).
//!
//! For now on scenes whose system never changes: no inertia switch, no μ_as unknowns
//! joining at T_g0, no phase started by a condition (the sensitivities through a restart
//! are the fit issue's next step); others are refused with the fields that make them so.

use std::path::PathBuf;
use std::time::Instant;

use super::{RunError, build_model, output_times};
use crate::case::overrides::{Override, number_at};
use crate::case::{Case, InertiaMode};
use crate::dae::sensitivity::{Perturbed, PerturbedModel};
use crate::dae::{Atol, Integrator};
use crate::model::observables::COLUMNS;
use crate::sundials::{Ida, SensitivityMethod, SensitivityOptions};

/// Why a sensitivity run could not start or finish.
#[derive(Debug, thiserror::Error)]
pub enum SensitivityError {
    /// Bad input: a parameter that is not a number field, a case this cannot follow.
    #[error("{0}")]
    Input(String),
    /// The case's model or an output failed as in a run.
    #[error(transparent)]
    Run(#[from] RunError),
    /// The integration stopped.
    #[error("integration stopped: {0}")]
    Integration(#[from] crate::dae::IntegratorError),
}

/// The relative step of the perturbed models (`F_p` by their residuals' differences).
pub const MODEL_STEP: f64 = 1e-7;

/// The relative step of the measures along the sensitivities (central differences).
pub const RELATIVE_STEP: f64 = 1e-4;

/// What to differentiate.
#[derive(Debug, Clone)]
pub struct SensitivityRequest {
    /// The case, and the file it came from (for messages).
    pub case: Case,
    pub file: String,
    /// Dotted case paths of the parameters (numbers).
    pub params: Vec<String>,
    /// Where `sensitivity.csv` goes.
    pub out: PathBuf,
    /// Include the sensitivities in IDAS's error test (their accuracy controlled too, at
    /// the price of more steps); otherwise the solution's steps carry them.
    pub error_control: bool,
    /// Show a progress bar (on a terminal).
    pub progress: bool,
}

/// One output time's measures and their derivatives.
#[derive(Debug, Clone)]
pub struct SensitivityRow {
    /// Time \[s\].
    pub t: f64,
    /// The measures (timeseries.csv's columns after `t`).
    pub values: Vec<f64>,
    /// Per parameter, ∂m/∂p of each measure.
    pub derivatives: Vec<Vec<f64>>,
}

/// A sensitivity run's result.
#[derive(Debug, Clone)]
pub struct SensitivityReport {
    /// The parameters and their values.
    pub params: Vec<(String, f64)>,
    /// One row per output time.
    pub rows: Vec<SensitivityRow>,
    /// Wall time of the integration with the sensitivities \[s\].
    pub wall_seconds: f64,
    /// Steps taken.
    pub steps: u64,
}

impl SensitivityReport {
    /// The normalised sensitivities p/m ∂m/∂p of the last row: per parameter, per measure
    /// (NaN where m = 0).
    pub fn final_normalised(&self) -> Vec<Vec<f64>> {
        let Some(last) = self.rows.last() else {
            return Vec::new();
        };
        self.params
            .iter()
            .zip(&last.derivatives)
            .map(|((_, p), d)| {
                d.iter()
                    .zip(&last.values)
                    .map(|(d, m)| if *m == 0.0 { f64::NAN } else { p / m * d })
                    .collect()
            })
            .collect()
    }
}

/// Why a case's system changes during the run, if it does (which this command cannot
/// follow yet): the fields that make it so.
pub fn restarts(case: &Case) -> Vec<&'static str> {
    let mut why = Vec::new();
    if matches!(case.inertia.mode, InertiaMode::OffAfter(_)) {
        why.push("inertia.mode = OffAfter (inertia is switched off during the run)");
    }
    if case.adhesion.is_some() && case.solver.defer_adhesion {
        why.push("solver.defer_adhesion = true with adhesion (the μ_as unknowns join at T_g0)");
    }
    if case.phases.adhesion_start.is_some() || case.phases.active_start.is_some() {
        why.push("phases.adhesion_start / active_start (a phase started by a condition)");
    }
    why
}

/// The case with `path` set to `value`.
fn with_value(req: &SensitivityRequest, path: &str, value: f64) -> Result<Case, SensitivityError> {
    let text = req
        .case
        .to_ron()
        .map_err(|e| SensitivityError::Input(e.to_string()))?;
    let o = Override::new(path, &format!("{value:e}"))
        .map_err(|e| SensitivityError::Input(format!("--param {path}: {e}")))?;
    Case::from_str_with_overrides(&text, &req.file, &[o])
        .map_err(|e| SensitivityError::Input(format!("--param {path} = {value:e}: {e}")))
}

/// Integrates the case with the sensitivities of `req.params`, writing
/// `sensitivity.csv` (per output time and parameter: the measures' derivatives) as it goes.
pub fn sensitivities(req: &SensitivityRequest) -> Result<SensitivityReport, SensitivityError> {
    let why = restarts(&req.case);
    if !why.is_empty() {
        return Err(SensitivityError::Input(format!(
            "{}: sensitivities through a change of the system are not implemented yet; this \
             case changes it: {}",
            req.file,
            why.join("; ")
        )));
    }
    if req.params.is_empty() {
        return Err(SensitivityError::Input("no --param given".into()));
    }
    let settings = req.case.solver.clone();
    let mut params = Vec::new();
    let mut perturbed = Vec::new();
    for path in &req.params {
        let v = number_at(&req.case, path).ok_or_else(|| {
            SensitivityError::Input(format!(
                "--param {path}: not a number field of {} (a dotted path, e.g. \
                 materials.cytoplasm.e)",
                req.file
            ))
        })?;
        if v == 0.0 || !v.is_finite() {
            return Err(SensitivityError::Input(format!(
                "--param {path}: its value {v} must be finite and nonzero (the steps are \
                 relative to it)"
            )));
        }
        // The step as the case holds it (the value is written in decimal).
        let case = with_value(req, path, v * (1.0 + MODEL_STEP))?;
        let delta = number_at(&case, path).unwrap_or(v) - v;
        let model = build_model(&case, &req.file, &settings)?;
        params.push((path.clone(), v));
        perturbed.push(PerturbedModel { model, delta });
    }
    let model = build_model(&req.case, &req.file, &settings)?;
    let atol = Atol::Vector(model.atol_vector(settings.atol));
    let linear_solver = if model.first_order_blocks().is_some() {
        settings.linear_solver
    } else {
        settings.linear_solver.uncondensed()
    };
    let opts = super::ida_options(&settings, atol, linear_solver);
    let dae =
        Perturbed::new(model, perturbed).map_err(|e| SensitivityError::Input(e.to_string()))?;
    let sens = SensitivityOptions {
        method: SensitivityMethod::Staggered,
        error_control: req.error_control,
        scales: params.iter().map(|(_, v)| v.abs()).collect(),
    };
    let start = Instant::now();
    let mut ida = Ida::with_sensitivities(dae, opts, sens)?;
    std::fs::create_dir_all(&req.out).map_err(super::io_err(&req.out))?;
    let csv_path = req.out.join("sensitivity.csv");
    let mut csv = String::from("t,parameter,value");
    for c in &COLUMNS[1..] {
        csv.push_str(&format!(",d_{c}"));
    }
    csv.push('\n');
    let mut rows = Vec::new();
    let bar = super::progress_bar(&req.case, req.progress);
    for t in output_times(&req.case) {
        ida.advance_to(t, &mut |t, _| {
            bar.set_position((t * 1000.0).round() as u64);
            true
        })?;
        let s = ida
            .sensitivities(0)
            .expect("the integrator carries sensitivities")?;
        let y = ida.y().to_vec();
        let model = &ida.dae().model;
        let measures = |y: &[f64]| model.observe(t, y).0.values()[1..].to_vec();
        let values = measures(&y);
        let mut derivatives = Vec::new();
        for ((name, p), si) in params.iter().zip(&s) {
            let hp = RELATIVE_STEP * p.abs();
            let shifted = |sign: f64| -> Vec<f64> {
                y.iter().zip(si).map(|(y, s)| y + sign * hp * s).collect()
            };
            let (up, down) = (measures(&shifted(1.0)), measures(&shifted(-1.0)));
            let d: Vec<f64> = up
                .iter()
                .zip(&down)
                .map(|(a, b)| (a - b) / (2.0 * hp))
                .collect();
            csv.push_str(&format!("{t},{name},{p}"));
            for v in &d {
                csv.push_str(&format!(",{v}"));
            }
            csv.push('\n');
            derivatives.push(d);
        }
        std::fs::write(&csv_path, &csv).map_err(super::io_err(&csv_path))?;
        rows.push(SensitivityRow {
            t,
            values,
            derivatives,
        });
    }
    bar.finish_and_clear();
    Ok(SensitivityReport {
        params,
        rows,
        wall_seconds: start.elapsed().as_secs_f64(),
        steps: ida.stats().steps,
    })
}
