//! `cellsim sensitivity`: the derivatives of a scene's measures with respect to case
//! parameters, integrated by IDAS with the solution ([`crate::dae::sensitivity`]): the
//! state's sensitivities `∂y/∂p` exactly (to the integrator's tolerance), a measure's
//! `∂m/∂p = (m(y + hp s) − m(y − hp s)) / 2hp` along them (`h` = 1e-4).
//!
//! Through the changes of system a run makes: the μ_as unknowns are in the system from
//! the start (`defer_adhesion` is a way of integrating the same model, not another model:
//! deferred, the exposure is integrated beside the system until T_g0), and where inertia is
//! switched off (`OffAfter`) the sensitivities restart consistently with the state, which
//! is set at rest in equilibrium: s of the displacements and ṡ of μ_as solved from the
//! linearised equilibrium, F_y s + F_ẏ ṡ + F_p = 0 ([`Perturbed::consistent_sensitivities`]).
//! The switch moment depends on the parameters only through which step first has the
//! contact carry the weight (a discrete choice, not differentiated), and the equilibrium
//! there on the time only through the gravity ramp, 10⁻⁸ of its final value at 10 s.
//! Phases started by a condition are refused.

use std::path::PathBuf;
use std::time::Instant;

use super::{Cell, RunError, build_model, output_times};
use crate::case::overrides::{Override, number_at};
use crate::case::{Case, InertiaMode};
use crate::dae::sensitivity::{Perturbed, PerturbedModel};
use crate::dae::{Atol, Dae, Integrator, IntegratorError, State};
use crate::model::Restart;
use crate::model::observables::COLUMNS;
use crate::solver::Settings;
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

/// Why a case's system changes during the run in a way this command cannot follow, if it
/// does: the fields that make it so.
pub fn restarts(case: &Case) -> Vec<&'static str> {
    let mut why = Vec::new();
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
    // The μ_as unknowns from the start: the same model without the restart at T_g0.
    let mut settings = req.case.solver.clone();
    settings.defer_adhesion = false;
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
    let dae =
        Perturbed::new(model, perturbed).map_err(|e| SensitivityError::Input(e.to_string()))?;
    let sens = SensitivityOptions {
        method: SensitivityMethod::Staggered,
        error_control: req.error_control,
        scales: params.iter().map(|(_, v)| v.abs()).collect(),
    };
    let ph = &req.case.phases;
    let mut switch_after = match req.case.inertia.mode {
        InertiaMode::OffAfter(ts) if ts < ph.t_end => Some(ts),
        _ => None,
    };
    let start = Instant::now();
    let mut ida = integrator(dae, &settings, sens.clone())?;
    let mut steps_before = 0;
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
        if let Some(ts) = switch_after {
            if ida.t() >= ts {
                if let Some(new) = switch_when_carried(&mut ida, ts, t, &settings, &sens)? {
                    steps_before += ida.stats().steps;
                    ida = new;
                    switch_after = None;
                } else if ida.t() > ts + crate::run::SWITCH_PROBE_LIMIT {
                    return Err(SensitivityError::Input(format!(
                        "{}: inertia.mode = OffAfter({ts}): the contact did not carry the \
                         cell's weight within {} s after the switch time",
                        req.file,
                        crate::run::SWITCH_PROBE_LIMIT
                    )));
                }
            }
        }
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
        steps: steps_before + ida.stats().steps,
    })
}

/// IDAS on `dae` with the run's options for its system and the sensitivities `sens`.
fn integrator(
    dae: Perturbed<Cell>,
    settings: &Settings,
    sens: SensitivityOptions,
) -> Result<Ida<Perturbed<Cell>>, SensitivityError> {
    let atol = Atol::Vector(dae.model.atol_vector(settings.atol));
    let linear_solver = if dae.model.first_order_blocks().is_some() {
        settings.linear_solver
    } else {
        settings.linear_solver.uncondensed()
    };
    let opts = super::ida_options(settings, atol, linear_solver);
    Ok(Ida::with_sensitivities(dae, opts, sens)?)
}

/// Steps on towards `tout` one at a time, from the requested switch time `ts`, and at the
/// first accepted step where the contact carries the cell's weight switches inertia off as
/// a run does ([`crate::run`]'s `advance_switching`), with the sensitivities restarted
/// consistently. `None` when `tout` came first.
fn switch_when_carried(
    ida: &mut Ida<Perturbed<Cell>>,
    ts: f64,
    tout: f64,
    settings: &Settings,
    sens: &SensitivityOptions,
) -> Result<Option<Ida<Perturbed<Cell>>>, SensitivityError> {
    loop {
        let (t, y, yp) = {
            let (t, y, yp) = ida.last_step();
            (t, y.to_vec(), yp.to_vec())
        };
        if t >= ts && t <= tout && ida.dae().model.contact_carries_weight(t, &y) {
            return switched(ida, t, &y, &yp, settings, sens).map(Some);
        }
        if ida.t() >= tout {
            return Ok(None);
        }
        match ida.advance_to(tout, &mut |_, _| false) {
            Ok(()) | Err(IntegratorError::Interrupted { .. }) => {}
            Err(e) => return Err(e.into()),
        }
    }
}

/// The integrator after inertia is switched off at the accepted step (`t`, `y`, `yp`):
/// the state at rest in equilibrium (as in a run), the perturbed problems on the same
/// state, and the sensitivities of the displacements and the rates of μ_as solved for.
fn switched(
    ida: &mut Ida<Perturbed<Cell>>,
    t: f64,
    y: &[f64],
    yp: &[f64],
    settings: &Settings,
    sens: &SensitivityOptions,
) -> Result<Ida<Perturbed<Cell>>, SensitivityError> {
    let fail =
        |e: String| SensitivityError::Input(format!("switching inertia off at t = {t} s: {e}"));
    let none = || fail("the integrator carries no sensitivities".into());
    let s = ida.sensitivities_at(t, 0).ok_or_else(none)??;
    let sp = ida.sensitivities_at(t, 1).ok_or_else(none)??;
    let uncondensed = settings.linear_solver.uncondensed();
    let restart = Restart {
        linear_solver: &uncondensed,
        rtol: settings.rtol,
        atol: settings.atol,
    };
    let old = ida.dae();
    let m2 = old
        .model
        .without_inertia_at_rest(State { t, y, yp }, &restart)
        .map_err(|e| fail(e.to_string()))?;
    let (_, y2, yp2) = m2.initial();
    let perturbed = old
        .perturbed
        .iter()
        .map(|p| {
            Ok(PerturbedModel {
                model: p
                    .model
                    .without_inertia_from(t, y2.clone(), yp2.clone())
                    .map_err(|e| fail(e.to_string()))?,
                delta: p.delta,
            })
        })
        .collect::<Result<Vec<_>, SensitivityError>>()?;
    // In the new layout: s of (u, μ_as); ṡ of u is 0 (at rest), of μ_as carried.
    let n_u = m2.unknowns().0;
    let (s2, sp2): (Vec<Vec<f64>>, Vec<Vec<f64>>) = s
        .iter()
        .zip(&sp)
        .map(|(si, spi)| {
            let (a, mut b) = old.model.drop_inertia(si, spi);
            b[..n_u].iter_mut().for_each(|v| *v = 0.0);
            (a, b)
        })
        .unzip();
    let mut dae = Perturbed::new(m2, perturbed).map_err(|e| fail(e.to_string()))?;
    let for_y: Vec<bool> = (0..dae.model.size()).map(|i| i < n_u).collect();
    dae.consistent_sensitivities(
        State {
            t,
            y: &y2,
            yp: &yp2,
        },
        &for_y,
        s2,
        sp2,
        &uncondensed,
    )?;
    integrator(dae, settings, sens.clone())
}
