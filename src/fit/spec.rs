//! The fit file (`cellsim fit FIT.ron`) and its checks: the cases, the parameters with
//! their bounds and scales, the targets. Every error names the file, and the field or the
//! line where it can.
//!
//! ```ron
//! (
//!     name: "twin",
//!     cases: [
//!         (name: "pp", file: "../fast/push-pull-short-drag.ron", set: ["solver.defer_adhesion=false"]),
//!     ],
//!     parameters: [
//!         (path: "materials.cytoplasm.e", lower: 100.0, upper: 10000.0, scale: Log, start: Some(700.0)),
//!         (path: "active.bottom.e", lower: 0.0, upper: 0.9),
//!     ],
//!     targets: [
//!         Series(case: "pp", file: "twin-data.csv"),   // rows t,column,value,sigma
//!         Final(case: "pp", measure: "penetration_depth", value: 3.2, sigma: 0.05),
//!         Point(case: "pp", measure: "uy_top", t: 500.0, value: -3.0, sigma: 0.1),
//!     ],
//! )
//! ```

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::case::overrides::number_at;
use crate::case::{Case, Override};
use crate::model::observables::COLUMNS;

/// The measures a target may name: `timeseries.csv`'s columns after `t`, and the nucleus
/// penetration depth between the pillars (as the sweeps report it).
pub fn measure_names() -> Vec<&'static str> {
    COLUMNS[1..]
        .iter()
        .copied()
        .chain(std::iter::once(PENETRATION))
        .collect()
}

/// The derived measure's name.
pub const PENETRATION: &str = "penetration_depth";

fn one() -> f64 {
    1.0
}

fn default_max_iterations() -> usize {
    20
}

fn default_difference_step() -> f64 {
    1e-2
}

fn default_first_step() -> f64 {
    0.1
}

/// How a parameter is varied: its logarithm (moduli, rates: positive, spanning decades) or
/// its value in units of its start; z = 0 at the start either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, serde::Serialize)]
pub enum Scale {
    /// z = ln(p / p₀), p₀ the start (> 0).
    Log,
    /// z = (p − p₀) / |p₀| (|p₀| replaced by 1 if p₀ = 0).
    #[default]
    Linear,
}

/// Where the gradients come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, serde::Serialize)]
pub enum Gradient {
    /// Forward sensitivities integrated by IDAS with the solution (through the inertia
    /// switch); central differences of whole runs for a case with a phase started by a
    /// condition.
    #[default]
    Sensitivities,
    /// Central differences of whole runs for every case (the check of the sensitivities).
    Differences,
}

/// A case of the fit.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseSpec {
    /// The name targets use.
    pub name: String,
    /// The case file, relative to the fit file.
    pub file: String,
    /// Overrides applied to it first (`PATH=VALUE`).
    #[serde(default)]
    pub set: Vec<String>,
}

/// A fitted parameter: the same dotted path in every case of the fit.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParameterSpec {
    /// Dotted path of a number field, e.g. `materials.cytoplasm.e`.
    pub path: String,
    /// Bounds.
    pub lower: f64,
    pub upper: f64,
    /// How it is varied.
    #[serde(default)]
    pub scale: Scale,
    /// Where the fit starts (default: the value in the first case it applies to).
    #[serde(default)]
    pub start: Option<f64>,
    /// The cases it applies to, by name (default: every case; a parameter the other cases
    /// do not have, e.g. the actin cap's strain, which the flat scene has no cap for).
    #[serde(default)]
    pub cases: Option<Vec<String>>,
}

/// What the fit matches.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum TargetSpec {
    /// A measure at the end of the case's run.
    Final {
        case: String,
        measure: String,
        value: f64,
        sigma: f64,
        #[serde(default = "one")]
        weight: f64,
    },
    /// The lowest value of a measure over the run (the paper's "maximum displacement of
    /// the nucleus" is minus the lowest `uy_nucleus_max`: `value` is the lowest, −5.4 µm
    /// for 5.4 µm down).
    Lowest {
        case: String,
        measure: String,
        value: f64,
        sigma: f64,
        #[serde(default = "one")]
        weight: f64,
    },
    /// A measure at a time.
    Point {
        case: String,
        measure: String,
        t: f64,
        value: f64,
        sigma: f64,
        #[serde(default = "one")]
        weight: f64,
    },
    /// A time series: a CSV file (relative to the fit file) with the header
    /// `t,column,value,sigma`, one measurement per row.
    Series {
        case: String,
        file: String,
        #[serde(default = "one")]
        weight: f64,
    },
}

/// The fit file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitFile {
    /// Name of the fit (its output directory's default name).
    pub name: String,
    /// The cases (one or several scenes sharing the parameters).
    pub cases: Vec<CaseSpec>,
    /// The parameters fitted.
    pub parameters: Vec<ParameterSpec>,
    /// The targets.
    pub targets: Vec<TargetSpec>,
    /// Where the gradients come from.
    #[serde(default)]
    pub gradient: Gradient,
    /// Levenberg–Marquardt iterations at most.
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// Step of the central differences, in the scaled parameter z.
    #[serde(default = "default_difference_step")]
    pub difference_step: f64,
    /// The first step's bound, as a fraction of the residuals' norm at the start (the
    /// trust region's radius in Levenberg–Marquardt's scaled norm, in which a step of
    /// that size changes the residuals by about that much): a first step that leaps
    /// across the parameter space can land in another basin of the misfit.
    #[serde(default = "default_first_step")]
    pub first_step: f64,
}

/// A case, loaded.
#[derive(Debug, Clone)]
pub struct FitCase {
    /// Its name in the fit file.
    pub name: String,
    /// The case file.
    pub file: PathBuf,
    /// The fit file's overrides of it.
    pub set: Vec<Override>,
    /// The case with them (the parameters at the case's own values).
    pub case: Case,
}

/// A parameter, checked.
#[derive(Debug, Clone)]
pub struct Param {
    pub path: String,
    pub lower: f64,
    pub upper: f64,
    pub scale: Scale,
    pub start: f64,
    /// The unit of z for a linear scale (|start|, or 1).
    pub unit: f64,
    /// The cases it applies to (indices).
    pub cases: Vec<usize>,
}

impl Param {
    /// z of a value p (0 at the start).
    pub fn to_z(&self, p: f64) -> f64 {
        match self.scale {
            Scale::Log => (p / self.start).ln(),
            Scale::Linear => (p - self.start) / self.unit,
        }
    }

    /// The value p of z.
    pub fn from_z(&self, z: f64) -> f64 {
        match self.scale {
            Scale::Log => self.start * z.exp(),
            Scale::Linear => self.start + z * self.unit,
        }
    }

    /// dp/dz at p.
    pub fn dp_dz(&self, p: f64) -> f64 {
        match self.scale {
            Scale::Log => p,
            Scale::Linear => self.unit,
        }
    }
}

/// Where in a run a datum is taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum When {
    /// At a time \[s\] (linear between output times).
    At(f64),
    /// At the end of the run.
    End,
    /// Where the measure is lowest over the run's output times.
    Lowest,
}

/// One measurement.
#[derive(Debug, Clone, PartialEq)]
pub struct Datum {
    /// Index of its case.
    pub case: usize,
    /// Index of its measure in [`measure_names`].
    pub measure: usize,
    /// Where in the run.
    pub when: When,
    pub value: f64,
    pub sigma: f64,
    pub weight: f64,
}

/// A fit file, loaded and checked.
#[derive(Debug, Clone)]
pub struct Fit {
    pub name: String,
    /// The fit file.
    pub file: PathBuf,
    pub cases: Vec<FitCase>,
    pub params: Vec<Param>,
    pub data: Vec<Datum>,
    pub gradient: Gradient,
    pub max_iterations: usize,
    pub difference_step: f64,
    pub first_step: f64,
    /// The Series targets: case index, data file, weight (for `--make-data`).
    pub series: Vec<(usize, PathBuf, f64)>,
}

/// Reads and checks `path`. With `read_series` false the time-series files are not read
/// (`--make-data` writes them).
pub fn load(path: &Path, read_series: bool) -> Result<Fit, String> {
    let label = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{label}: cannot read the fit file: {e}"))?;
    let spec: FitFile = ron::Options::default()
        .from_str(text.trim_start_matches('\u{FEFF}'))
        .map_err(|e| {
            format!(
                "{label}:{}:{}: {}",
                e.span.start.line, e.span.start.col, e.code
            )
        })?;
    resolve(path, spec, read_series).map_err(|m| format!("{label}: {m}"))
}

fn resolve(path: &Path, spec: FitFile, read_series: bool) -> Result<Fit, String> {
    let dir = path.parent().unwrap_or(Path::new("."));
    if spec.cases.is_empty() {
        return Err("cases: at least one case is needed".into());
    }
    if spec.parameters.is_empty() {
        return Err("parameters: at least one parameter is needed".into());
    }
    if spec.targets.is_empty() {
        return Err("targets: at least one target is needed".into());
    }
    if spec.max_iterations == 0 {
        return Err("max_iterations = 0: must be at least 1".into());
    }
    if !(spec.difference_step > 0.0 && spec.difference_step <= 0.5) {
        return Err(format!(
            "difference_step = {}: must be in (0, 0.5]",
            spec.difference_step
        ));
    }
    if !(spec.first_step > 0.0 && spec.first_step <= 100.0) {
        return Err(format!(
            "first_step = {}: must be in (0, 100]",
            spec.first_step
        ));
    }
    let mut cases: Vec<FitCase> = Vec::new();
    for (k, c) in spec.cases.iter().enumerate() {
        if cases.iter().any(|o| o.name == c.name) {
            return Err(format!("cases[{k}].name = {:?}: used twice", c.name));
        }
        let set = c
            .set
            .iter()
            .map(|s| {
                Override::parse(s)
                    .map(|o| o.from_source(format!("cases[{k}].set {s:?}")))
                    .map_err(|e| format!("cases[{k}].set {s:?}: {e}"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let file = dir.join(&c.file);
        let case = Case::load_with_overrides(&file, &set)
            .map_err(|e| format!("cases[{k}] ({:?}): {e}", c.name))?;
        cases.push(FitCase {
            name: c.name.clone(),
            file,
            set,
            case,
        });
    }
    let mut params: Vec<Param> = Vec::new();
    for (k, p) in spec.parameters.iter().enumerate() {
        let at = |m: String| format!("parameters[{k}] ({}): {m}", p.path);
        if params.iter().any(|o| o.path == p.path) {
            return Err(at("named twice".into()));
        }
        let applies: Vec<usize> = match &p.cases {
            None => (0..cases.len()).collect(),
            Some(names) if names.is_empty() => {
                return Err(at("cases = []: name at least one case".into()));
            }
            Some(names) => names
                .iter()
                .map(|n| {
                    cases
                        .iter()
                        .position(|c| &c.name == n)
                        .ok_or_else(|| at(format!("cases: {n:?} is not one of the fit's cases")))
                })
                .collect::<Result<_, _>>()?,
        };
        for c in applies.iter().map(|&k| &cases[k]) {
            if number_at(&c.case, &p.path).is_none() {
                return Err(at(format!(
                    "not a number field of case {:?} ({}): a dotted path, e.g. \
                     materials.cytoplasm.e",
                    c.name,
                    c.file.display()
                )));
            }
        }
        if !(p.lower.is_finite() && p.upper.is_finite() && p.lower < p.upper) {
            return Err(at(format!(
                "lower = {}, upper = {}: must be finite with lower < upper",
                p.lower, p.upper
            )));
        }
        if p.scale == Scale::Log && p.lower <= 0.0 {
            return Err(at(format!(
                "scale = Log needs lower > 0 (lower = {})",
                p.lower
            )));
        }
        let start = match p.start {
            Some(s) => s,
            None => number_at(&cases[applies[0]].case, &p.path).unwrap_or(f64::NAN),
        };
        if !(start >= p.lower && start <= p.upper) {
            return Err(at(format!(
                "start = {start} is outside [lower, upper] = [{}, {}]",
                p.lower, p.upper
            )));
        }
        let unit = if start != 0.0 { start.abs() } else { 1.0 };
        params.push(Param {
            path: p.path.clone(),
            lower: p.lower,
            upper: p.upper,
            scale: p.scale,
            start,
            unit,
            cases: applies,
        });
    }
    let names = measure_names();
    let case_index = |k: usize, name: &str| -> Result<usize, String> {
        cases.iter().position(|c| c.name == name).ok_or_else(|| {
            let known: Vec<&str> = cases.iter().map(|c| c.name.as_str()).collect();
            format!(
                "targets[{k}]: case {name:?} is not one of the fit's cases ({})",
                known.join(", ")
            )
        })
    };
    let measure_index = |k: usize, m: &str| -> Result<usize, String> {
        names.iter().position(|n| *n == m).ok_or_else(|| {
            format!(
                "targets[{k}]: measure {m:?} is not one of {}",
                names.join(", ")
            )
        })
    };
    let check_value = |k: usize, what: &str, v: f64| -> Result<(), String> {
        if v.is_finite() {
            Ok(())
        } else {
            Err(format!("targets[{k}]: {what} = {v} must be finite"))
        }
    };
    let check_positive = |k: usize, what: &str, v: f64| -> Result<(), String> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(format!("targets[{k}]: {what} = {v} must be > 0"))
        }
    };
    let mut data = Vec::new();
    let mut series = Vec::new();
    // A single measured value: checked, then recorded.
    let one =
        |k: usize, case: &str, measure: &str, when: When, value: f64, sigma: f64, weight: f64| {
            check_value(k, "value", value)?;
            check_positive(k, "sigma", sigma)?;
            check_positive(k, "weight", weight)?;
            Ok::<_, String>(Datum {
                case: case_index(k, case)?,
                measure: measure_index(k, measure)?,
                when,
                value,
                sigma,
                weight,
            })
        };
    for (k, t) in spec.targets.iter().enumerate() {
        match t {
            TargetSpec::Final {
                case,
                measure,
                value,
                sigma,
                weight,
            } => data.push(one(k, case, measure, When::End, *value, *sigma, *weight)?),
            TargetSpec::Lowest {
                case,
                measure,
                value,
                sigma,
                weight,
            } => data.push(one(
                k,
                case,
                measure,
                When::Lowest,
                *value,
                *sigma,
                *weight,
            )?),
            TargetSpec::Point {
                case,
                measure,
                t,
                value,
                sigma,
                weight,
            } => {
                let d = one(k, case, measure, When::At(*t), *value, *sigma, *weight)?;
                check_time(k, *t, &cases[d.case].case)?;
                data.push(d);
            }
            TargetSpec::Series { case, file, weight } => {
                let c = case_index(k, case)?;
                check_positive(k, "weight", *weight)?;
                let path = dir.join(file);
                if read_series {
                    for d in read_series_file(&path, c, *weight, &cases[c].case)
                        .map_err(|m| format!("targets[{k}]: {m}"))?
                    {
                        data.push(d);
                    }
                }
                series.push((c, path, *weight));
            }
        }
    }
    let uses_penetration = data.iter().any(|d| names[d.measure] == PENETRATION);
    if uses_penetration {
        if let Some(p) = params
            .iter()
            .find(|p| p.path.starts_with("substrate.") || p.path.starts_with("geometry."))
        {
            return Err(format!(
                "parameters ({}): a target is the penetration depth, measured from the pillar \
                 tops, which this parameter moves; fit it without that target",
                p.path
            ));
        }
    }
    Ok(Fit {
        name: spec.name,
        file: path.to_path_buf(),
        cases,
        params,
        data,
        gradient: spec.gradient,
        max_iterations: spec.max_iterations,
        difference_step: spec.difference_step,
        first_step: spec.first_step,
        series,
    })
}

/// A target's time must lie in (0, t_end] of its case.
fn check_time(k: usize, t: f64, case: &Case) -> Result<(), String> {
    let t_end = case.phases.t_end;
    if t.is_finite() && t > 0.0 && t <= t_end {
        Ok(())
    } else {
        Err(format!(
            "targets[{k}]: t = {t} is outside the case's run (0, t_end = {t_end}] s"
        ))
    }
}

/// The header of a time-series file.
pub const SERIES_HEADER: &str = "t,column,value,sigma";

/// Reads a time-series file: header [`SERIES_HEADER`], then `t,column,value,sigma` rows.
fn read_series_file(path: &Path, case: usize, weight: f64, c: &Case) -> Result<Vec<Datum>, String> {
    let label = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{label}: cannot read: {e}"))?;
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim() == SERIES_HEADER => {}
        Some((_, h)) => {
            return Err(format!(
                "{label}:1: the header is {h:?}, expected {SERIES_HEADER:?}"
            ));
        }
        None => return Err(format!("{label}: empty")),
    }
    let names = measure_names();
    let mut out = Vec::new();
    for (i, line) in lines {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let at = |m: String| format!("{label}:{}: {m}", i + 1);
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 4 {
            return Err(at(format!(
                "{} fields, expected 4 ({SERIES_HEADER})",
                f.len()
            )));
        }
        let num = |s: &str, what: &str| -> Result<f64, String> {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| at(format!("{what} = {s:?} is not a finite number")))
        };
        let t = num(f[0], "t")?;
        let t_end = c.phases.t_end;
        if !(t > 0.0 && t <= t_end) {
            return Err(at(format!(
                "t = {t} is outside the case's run (0, t_end = {t_end}] s"
            )));
        }
        let measure = names.iter().position(|n| *n == f[1]).ok_or_else(|| {
            at(format!(
                "column {:?} is not one of {}",
                f[1],
                names.join(", ")
            ))
        })?;
        let value = num(f[2], "value")?;
        let sigma = num(f[3], "sigma")?;
        if sigma <= 0.0 {
            return Err(at(format!("sigma = {sigma} must be > 0")));
        }
        out.push(Datum {
            case,
            measure,
            when: When::At(t),
            value,
            sigma,
            weight,
        });
    }
    if out.is_empty() {
        return Err(format!("{label}: no rows"));
    }
    Ok(out)
}
