//! `cellsim fit FIT.ron`: the case parameters that reproduce measurements, by weighted
//! least squares (Levenberg–Marquardt with bounds: [`rmpfit`], a port of CMPFIT), with
//! their standard errors, correlations and what the data cannot determine.
//!
//! The residuals are `wᵢ (mᵢ(p) − dᵢ) / σᵢ`, `mᵢ` a measure of a case's run at a time
//! (linear between output times) or at its end. The parameters are fitted in scaled form
//! `z` ([`spec::Scale`]: `ln(p/p₀)`, or `p − p₀` in units of the start p₀), so that the Jacobian's
//! columns are comparable: its singular values and vectors say which combinations the data
//! determine. Gradients come from the forward sensitivities integrated by IDAS with the
//! solution ([`crate::run::sensitivity`]), and from central differences of whole runs for
//! a case with a phase started by a condition (or everywhere, with
//! `gradient: Differences`: the check).
//!
//! A run that fails at a trial point is reported and counted as a step that increased the
//! misfit a hundredfold, so that the algorithm shortens its step; a failure at the start
//! or where a gradient is needed ends the fit with the run's message.

pub mod spec;

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use serde::Serialize;

use crate::case::{Case, Override};
use crate::run::sensitivity::{SensitivityRequest, restarts, sensitivities};
use crate::run::{self, RunOptions};
use spec::{Datum, Fit, Gradient, Param, Scale, When, measure_names};

/// A case's measures over its run: per output time, each of [`measure_names`]; with the
/// sensitivities, per parameter ∂m/∂p at each time.
#[derive(Debug, Clone)]
pub struct Curves {
    pub t: Vec<f64>,
    pub values: Vec<Vec<f64>>,
    /// `[parameter][row][measure]`.
    pub derivatives: Option<Vec<Vec<Vec<f64>>>>,
    /// The case's end time.
    pub t_end: f64,
}

impl Curves {
    /// The rows and weights that give measure `m` at `when`: linear between output times,
    /// or the row where `m` is lowest.
    fn at(&self, m: usize, when: When) -> Result<[(usize, f64); 2], String> {
        let n = self.t.len();
        if n == 0 {
            return Err("the run wrote no output".into());
        }
        let tol = 1e-9 * self.t_end.max(1.0);
        let t = match when {
            When::Lowest => {
                let k = (0..n)
                    .min_by(|&a, &b| self.values[a][m].total_cmp(&self.values[b][m]))
                    .expect("n > 0");
                return Ok([(k, 1.0), (k, 0.0)]);
            }
            When::End => self.t_end,
            When::At(t) => t,
        };
        if t > self.t[n - 1] + tol {
            return Err(format!(
                "the run reached t = {} s only, short of t = {t} s",
                self.t[n - 1]
            ));
        }
        if t < self.t[0] - tol {
            return Err(format!(
                "t = {t} s is before the first output time {} s",
                self.t[0]
            ));
        }
        let k = self.t.partition_point(|&x| x < t - tol).min(n - 1);
        if (self.t[k] - t).abs() <= tol || k == 0 {
            return Ok([(k, 1.0), (k, 0.0)]);
        }
        let (t0, t1) = (self.t[k - 1], self.t[k]);
        let w = (t - t0) / (t1 - t0);
        Ok([(k - 1, 1.0 - w), (k, w)])
    }

    /// The value of measure `m` at `when`.
    pub fn value(&self, m: usize, when: When) -> Result<f64, String> {
        let w = self.at(m, when)?;
        Ok(w.iter().map(|(k, a)| a * self.values[*k][m]).sum())
    }

    /// The time of measure `m` at `when`.
    pub fn time(&self, m: usize, when: When) -> Result<f64, String> {
        let w = self.at(m, when)?;
        Ok(w.iter().map(|(k, a)| a * self.t[*k]).sum())
    }

    /// ∂m/∂p_j at `when` (the sensitivities must be there; at the lowest row, the
    /// derivative there: the envelope of the rows).
    fn derivative(&self, j: usize, m: usize, when: When) -> Result<f64, String> {
        let d = self
            .derivatives
            .as_ref()
            .ok_or("no sensitivities were integrated")?;
        let w = self.at(m, when)?;
        Ok(w.iter().map(|(k, a)| a * d[j][*k][m]).sum())
    }
}

/// The case `k` of the fit with the parameters `p`.
pub fn case_at(fit: &Fit, k: usize, p: &[f64]) -> Result<Case, String> {
    let c = &fit.cases[k];
    let mut set = c.set.clone();
    for (param, v) in fit
        .params
        .iter()
        .zip(p)
        .filter(|(q, _)| q.cases.contains(&k))
    {
        set.push(
            Override::new(&param.path, &format!("{v:e}"))
                .map_err(|e| format!("{} = {v:e}: {e}", param.path))?,
        );
    }
    Case::load_with_overrides(&c.file, &set).map_err(|e| format!("{} = {p:?}: {e}", c.name))
}

/// The penetration depth of the nucleus with `uy_bottom` (the sweeps' measure).
fn penetration(case: &Case, uy_bottom: f64) -> f64 {
    crate::commands::sweep::table::penetration_depth(case, uy_bottom)
}

/// Index of `uy_bottom` among the measures.
fn uy_bottom_index() -> usize {
    measure_names()
        .iter()
        .position(|n| *n == "uy_bottom")
        .expect("a column of timeseries.csv")
}

/// Runs case `k` at `p` into `dir`: the measures over time, and their sensitivities with
/// `sensitive`.
pub fn evaluate(
    fit: &Fit,
    k: usize,
    p: &[f64],
    sensitive: bool,
    dir: &Path,
) -> Result<Curves, String> {
    let case = case_at(fit, k, p)?;
    let file = fit.cases[k].file.display().to_string();
    let ib = uy_bottom_index();
    let t_end = case.phases.t_end;
    if sensitive {
        // The parameters of this case; the others' derivatives are 0.
        let own: Vec<usize> = (0..fit.params.len())
            .filter(|&j| fit.params[j].cases.contains(&k))
            .collect();
        let req = SensitivityRequest {
            case: case.clone(),
            file: file.clone(),
            params: own.iter().map(|&j| fit.params[j].path.clone()).collect(),
            out: dir.to_path_buf(),
            error_control: false,
            progress: false,
        };
        let report = sensitivities(&req).map_err(|e| e.to_string())?;
        let mut t = Vec::new();
        let mut values = Vec::new();
        let mut derivatives = vec![Vec::new(); fit.params.len()];
        for row in &report.rows {
            t.push(row.t);
            let mut v = row.values.clone();
            let pen = penetration(&case, v[ib]);
            v.push(pen);
            let zeros = vec![0.0; v.len()];
            values.push(v);
            for (j, list) in derivatives.iter_mut().enumerate() {
                match own.iter().position(|&o| o == j) {
                    Some(i) => {
                        let mut d = row.derivatives[i].clone();
                        d.push(if pen > 0.0 { -d[ib] } else { 0.0 });
                        list.push(d);
                    }
                    None => list.push(zeros.clone()),
                }
            }
        }
        return Ok(Curves {
            t,
            values,
            derivatives: Some(derivatives),
            t_end,
        });
    }
    let opts = RunOptions::new(dir, case.solver.clone());
    let summary = run::run(&case, &file, &opts).map_err(|e| e.to_string())?;
    let path = dir.join("timeseries.csv");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let (rows, _) =
        crate::run_files::read::parse_timeseries(&path, &text).map_err(|e| e.to_string())?;
    if !summary.finished {
        let why = summary
            .failure
            .map(|f| f.reason)
            .unwrap_or_else(|| "it did not finish".into());
        return Err(format!("the run stopped: {why}"));
    }
    let mut t = Vec::new();
    let mut values = Vec::new();
    for o in rows.iter().filter(|o| o.t > 0.0) {
        t.push(o.t);
        let mut v = o.values()[1..].to_vec();
        v.push(penetration(&case, v[ib]));
        values.push(v);
    }
    Ok(Curves {
        t,
        values,
        derivatives: None,
        t_end,
    })
}

/// Runs `tasks` on `jobs` threads, each with `f`; results in task order.
fn parallel<T: Sync, R: Send>(tasks: &[T], jobs: usize, f: &(dyn Fn(&T) -> R + Sync)) -> Vec<R> {
    let queue = Mutex::new((0..tasks.len()).collect::<VecDeque<_>>());
    let results: Mutex<Vec<Option<R>>> = Mutex::new((0..tasks.len()).map(|_| None).collect());
    let jobs = jobs.clamp(1, tasks.len().max(1));
    crate::solver::share_cores_among(jobs);
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| {
                loop {
                    let next = queue.lock().expect("queue").pop_front();
                    let Some(i) = next else { break };
                    let r = f(&tasks[i]);
                    results.lock().expect("results")[i] = Some(r);
                }
            });
        }
    });
    results
        .into_inner()
        .expect("results")
        .into_iter()
        .map(|r| r.expect("every task ran"))
        .collect()
}

/// One line of `history.csv`.
#[derive(Debug, Clone, Serialize)]
pub struct HistoryRow {
    pub evaluation: usize,
    /// `trial` (a point the algorithm tries) or `gradient`.
    pub kind: &'static str,
    pub chi2: f64,
    pub params: Vec<f64>,
    pub seconds: f64,
    /// Empty, or why a run failed.
    pub status: String,
}

/// The fit as [`rmpfit`] sees it.
struct Problem<'a> {
    fit: &'a Fit,
    out: PathBuf,
    jobs: usize,
    /// Whether each case gets its gradient from the sensitivities.
    sensitive: Vec<bool>,
    /// Curves of recent points (z, per case).
    cache: VecDeque<(Vec<f64>, Vec<Curves>)>,
    history: Vec<HistoryRow>,
    /// The smallest χ² met.
    best: f64,
    quiet: bool,
    /// rmpfit's parameter constraints (the bounds in z) and configuration.
    pars: Vec<rmpfit::MPPar>,
    config: rmpfit::MPConfig,
}

impl<'a> Problem<'a> {
    /// The problem of `fit`, its runs in `out`, gradients from `gradient`.
    fn new(fit: &'a Fit, out: &Path, jobs: usize, gradient: Gradient, quiet: bool) -> Self {
        Problem {
            fit,
            out: out.to_path_buf(),
            jobs: jobs.max(1),
            sensitive: fit
                .cases
                .iter()
                .map(|c| gradient == Gradient::Sensitivities && restarts(&c.case).is_empty())
                .collect(),
            cache: VecDeque::new(),
            history: Vec::new(),
            best: f64::INFINITY,
            quiet,
            pars: fit
                .params
                .iter()
                .map(|p| rmpfit::MPPar {
                    limited_low: true,
                    limited_up: true,
                    limit_low: p.to_z(p.lower),
                    limit_up: p.to_z(p.upper),
                    side: rmpfit::MPSide::User,
                    ..Default::default()
                })
                .collect(),
            config: rmpfit::MPConfig {
                max_iter: fit.max_iterations,
                ftol: 1e-6,
                xtol: 1e-6,
                ..rmpfit::MPConfig::new()
            },
        }
    }

    fn params_of(&self, z: &[f64]) -> Vec<f64> {
        self.fit
            .params
            .iter()
            .zip(z)
            .map(|(p, z)| p.from_z(*z).clamp(p.lower, p.upper))
            .collect()
    }

    /// Every case's curves at z (the sensitivities where they are used).
    fn curves(&mut self, z: &[f64]) -> Result<Vec<Curves>, String> {
        if let Some((_, c)) = self.cache.iter().find(|(zc, _)| zc == z) {
            return Ok(c.clone());
        }
        let p = self.params_of(z);
        let tasks: Vec<usize> = (0..self.fit.cases.len()).collect();
        let fit = self.fit;
        let (out, sensitive) = (&self.out, &self.sensitive);
        let results = parallel(&tasks, self.jobs, &|&k| {
            let dir = out.join("runs").join(&fit.cases[k].name);
            evaluate(fit, k, &p, sensitive[k], &dir)
                .map_err(|e| format!("case {:?}: {e}", fit.cases[k].name))
        });
        let curves = results.into_iter().collect::<Result<Vec<_>, _>>()?;
        self.cache.push_front((z.to_vec(), curves.clone()));
        self.cache.truncate(4);
        Ok(curves)
    }

    /// The residuals of `curves`.
    fn deviates(&self, curves: &[Curves], out: &mut [f64]) -> Result<(), String> {
        let names = measure_names();
        for (r, d) in out.iter_mut().zip(&self.fit.data) {
            let m = curves[d.case].value(d.measure, d.when).map_err(|e| {
                format!(
                    "case {:?}, {}: {e}",
                    self.fit.cases[d.case].name, names[d.measure]
                )
            })?;
            *r = d.weight * (m - d.value) / d.sigma;
        }
        Ok(())
    }

    fn record(&mut self, kind: &'static str, z: &[f64], chi2: f64, t0: Instant, status: String) {
        let row = HistoryRow {
            evaluation: self.history.len() + 1,
            kind,
            chi2,
            params: self.params_of(z),
            seconds: t0.elapsed().as_secs_f64(),
            status,
        };
        if !self.quiet {
            let ps: Vec<String> = self
                .fit
                .params
                .iter()
                .zip(&row.params)
                .map(|(p, v)| format!("{} = {v:.6e}", p.path))
                .collect();
            let what = if row.status.is_empty() {
                format!("χ² = {chi2:.6e}")
            } else {
                format!("failed: {}", row.status)
            };
            eprintln!(
                "fit {}: evaluation {} ({kind}, {:.1} s): {what}; {}",
                self.fit.name,
                row.evaluation,
                row.seconds,
                ps.join(", ")
            );
        }
        self.history.push(row);
        let _ = write_history(&self.out, self.fit, &self.history);
    }

    /// The Jacobian of the residuals in z at z, per datum and parameter.
    fn jacobian_at(&mut self, z: &[f64]) -> Result<Vec<Vec<f64>>, String> {
        let fit = self.fit;
        let (m, n) = (fit.data.len(), fit.params.len());
        let p = self.params_of(z);
        let base = self.curves(z)?;
        let mut jac = vec![vec![0.0; n]; m];
        // Differences for the cases without sensitivities: 2 runs per parameter.
        let h = fit.difference_step;
        let tasks: Vec<(usize, usize, f64)> = (0..fit.cases.len())
            .filter(|&k| !self.sensitive[k])
            .flat_map(|k| {
                (0..n)
                    .filter(move |&j| fit.params[j].cases.contains(&k))
                    .flat_map(move |j| [(k, j, h), (k, j, -h)])
            })
            .collect();
        let out = &self.out;
        let runs = parallel(&tasks, self.jobs, &|&(k, j, dz)| {
            let mut zz = z.to_vec();
            zz[j] += dz;
            let pp: Vec<f64> = fit
                .params
                .iter()
                .zip(&zz)
                .map(|(q, z)| q.from_z(*z))
                .collect();
            let dir = out.join("runs").join(format!(
                "{}-d{j}{}",
                fit.cases[k].name,
                if dz > 0.0 { "+" } else { "-" }
            ));
            evaluate(fit, k, &pp, false, &dir)
        });
        for (i, d) in fit.data.iter().enumerate() {
            let w = d.weight / d.sigma;
            if self.sensitive[d.case] {
                for (j, q) in fit.params.iter().enumerate() {
                    let dm = base[d.case].derivative(j, d.measure, d.when)?;
                    jac[i][j] = w * dm * q.dp_dz(p[j]);
                }
                continue;
            }
            for j in (0..n).filter(|&j| fit.params[j].cases.contains(&d.case)) {
                let find = |sign: f64| {
                    tasks
                        .iter()
                        .position(|&(k, jj, dz)| k == d.case && jj == j && dz * sign > 0.0)
                        .and_then(|i| runs[i].as_ref().ok())
                        .map(|c| c.value(d.measure, d.when))
                };
                let m0 = base[d.case].value(d.measure, d.when)?;
                let dm = match (find(1.0), find(-1.0)) {
                    (Some(Ok(a)), Some(Ok(b))) => (a - b) / (2.0 * h),
                    (Some(Ok(a)), _) => (a - m0) / h,
                    (_, Some(Ok(b))) => (m0 - b) / h,
                    _ => {
                        let why: Vec<String> = tasks
                            .iter()
                            .zip(&runs)
                            .filter(|((k, jj, _), _)| *k == d.case && *jj == j)
                            .filter_map(|(_, r)| r.as_ref().err().cloned())
                            .collect();
                        return Err(format!(
                            "case {:?}: the runs at {} ± {h} (in z) failed: {}",
                            fit.cases[d.case].name,
                            fit.params[j].path,
                            why.join("; ")
                        ));
                    }
                };
                jac[i][j] = w * dm;
            }
        }
        Ok(jac)
    }
}

impl rmpfit::MPFitter for Problem<'_> {
    fn eval(&mut self, z: &[f64], deviates: &mut [f64]) -> rmpfit::MPResult<()> {
        let t0 = Instant::now();
        let result = self
            .curves(z)
            .and_then(|c| self.deviates(&c, deviates).map(|_| ()));
        match result {
            Ok(()) => {
                let chi2: f64 = deviates.iter().map(|r| r * r).sum();
                self.best = self.best.min(chi2);
                self.record("trial", z, chi2, t0, String::new());
                Ok(())
            }
            Err(e) if self.best.is_finite() => {
                // A failed run at a trial point: a misfit a hundredfold the best met, so
                // that the step is refused and shortened.
                let r = 10.0 * (self.best.max(1.0) / deviates.len() as f64).sqrt();
                deviates.iter_mut().for_each(|d| *d = r);
                self.record("trial", z, f64::NAN, t0, e);
                Ok(())
            }
            Err(e) => {
                self.record("trial", z, f64::NAN, t0, e);
                Err(rmpfit::MPError::Eval)
            }
        }
    }

    fn number_of_points(&self) -> usize {
        self.fit.data.len()
    }

    fn config(&self) -> &rmpfit::MPConfig {
        &self.config
    }

    fn parameters(&self) -> &[rmpfit::MPPar] {
        &self.pars
    }

    fn jacobian(
        &mut self,
        z: &[f64],
        deviates: &mut [f64],
        derivs: &mut [Option<Vec<f64>>],
    ) -> rmpfit::MPResult<()> {
        let t0 = Instant::now();
        let result = self.curves(z).and_then(|c| {
            self.deviates(&c, deviates)?;
            self.jacobian_at(z)
        });
        match result {
            Ok(jac) => {
                for (j, col) in derivs.iter_mut().enumerate() {
                    if let Some(col) = col {
                        for (i, c) in col.iter_mut().enumerate() {
                            *c = jac[i][j];
                        }
                    }
                }
                let chi2: f64 = deviates.iter().map(|r| r * r).sum();
                self.record("gradient", z, chi2, t0, String::new());
                Ok(())
            }
            Err(e) => {
                self.record("gradient", z, f64::NAN, t0, e);
                Err(rmpfit::MPError::Eval)
            }
        }
    }
}

fn write_history(out: &Path, fit: &Fit, rows: &[HistoryRow]) -> std::io::Result<()> {
    let mut s = String::from("evaluation,kind,chi2,seconds");
    for p in &fit.params {
        s.push_str(&format!(",{}", p.path));
    }
    s.push_str(",status\n");
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{:.3}",
            r.evaluation, r.kind, r.chi2, r.seconds
        ));
        for v in &r.params {
            s.push_str(&format!(",{v:e}"));
        }
        s.push_str(&format!(
            ",{}\n",
            crate::commands::sweep::table::field(&r.status)
        ));
    }
    std::fs::write(out.join("history.csv"), s)
}

/// A fitted parameter in `fit.json`.
#[derive(Debug, Clone, Serialize)]
pub struct FittedParam {
    pub path: String,
    pub scale: Scale,
    pub start: f64,
    pub value: f64,
    pub lower: f64,
    pub upper: f64,
    /// One standard error, from the Gauss–Newton Hessian at the fitted values (first order
    /// in z: `p σ_z` for a log scale).
    pub standard_error: f64,
    /// The standard error of z (of ln p on a log scale: the relative error).
    pub standard_error_z: f64,
    /// At a bound (its standard error is then not meaningful).
    pub at_bound: bool,
}

/// One singular value of the scaled sensitivity matrix and its parameter combination.
#[derive(Debug, Clone, Serialize)]
pub struct Direction {
    pub singular_value: f64,
    /// The combination of the scaled parameters (z), a unit vector.
    pub combination: Vec<(String, f64)>,
    /// The standard error of z along it (1 / the singular value).
    pub standard_error: f64,
}

/// `fit.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    pub name: String,
    pub fit_file: String,
    pub gradient: Gradient,
    /// Per case, whether its gradient came from the sensitivities or from differences.
    pub case_gradients: Vec<(String, String)>,
    pub termination: String,
    pub iterations: usize,
    pub evaluations: usize,
    pub chi2_start: f64,
    pub chi2: f64,
    pub data_points: usize,
    pub degrees_of_freedom: usize,
    pub reduced_chi2: f64,
    pub parameters: Vec<FittedParam>,
    /// Correlation matrix of the parameters (z), row by row.
    pub correlation: Vec<Vec<f64>>,
    /// The singular values of the scaled sensitivity matrix J (residuals against z),
    /// largest first, with their parameter combinations.
    pub directions: Vec<Direction>,
    /// The combinations the data cannot determine: standard error of z above 1 (a factor
    /// e on a log scale, a whole start value on a linear one).
    pub undetermined: Vec<Direction>,
    pub wall_seconds: f64,
}

/// What `cellsim fit` was asked.
#[derive(Debug, Clone)]
pub struct FitOptions {
    pub out: PathBuf,
    pub jobs: usize,
    pub quiet: bool,
}

/// Standard errors, correlations and directions from the Jacobian `jac` (data × params).
fn statistics(params: &[Param], jac: &[Vec<f64>]) -> (Vec<f64>, Vec<Vec<f64>>, Vec<Direction>) {
    let (m, n) = (jac.len(), params.len());
    let j = nalgebra::DMatrix::from_fn(m, n, |i, k| jac[i][k]);
    let svd = j.svd(false, true);
    let vt = svd.v_t.expect("asked for V");
    let s = svd.singular_values;
    let mut order: Vec<usize> = (0..s.len()).collect();
    order.sort_by(|a, b| s[*b].total_cmp(&s[*a]));
    let smax = order.first().map_or(0.0, |&k| s[k]);
    let mut cov = nalgebra::DMatrix::<f64>::zeros(n, n);
    for k in 0..s.len() {
        if s[k] > 1e-12 * smax {
            let v = vt.row(k).transpose();
            cov += &v * v.transpose() / (s[k] * s[k]);
        } else {
            for a in 0..n {
                cov[(a, a)] = f64::INFINITY;
            }
        }
    }
    let se_z: Vec<f64> = (0..n).map(|a| cov[(a, a)].sqrt()).collect();
    let corr = (0..n)
        .map(|a| (0..n).map(|b| cov[(a, b)] / (se_z[a] * se_z[b])).collect())
        .collect();
    let directions = order
        .iter()
        .map(|&k| Direction {
            singular_value: s[k],
            combination: params
                .iter()
                .enumerate()
                .map(|(a, p)| (p.path.clone(), vt[(k, a)]))
                .collect(),
            standard_error: 1.0 / s[k],
        })
        .collect();
    (se_z, corr, directions)
}

/// The Jacobian of the fit's residuals in z at its start (data × parameters), with the
/// gradients of `gradient` (the check of the sensitivities against differences), runs in
/// `out`.
pub fn jacobian_at_start(
    fit: &Fit,
    gradient: Gradient,
    out: &Path,
    jobs: usize,
) -> Result<Vec<Vec<f64>>, String> {
    let mut problem = Problem::new(fit, out, jobs, gradient, true);
    problem.jacobian_at(&vec![0.0; fit.params.len()])
}

/// Runs the fit; writes `fit.json`, `history.csv`, `residuals.csv` and the figures into
/// `opts.out`.
pub fn run_fit(fit: &Fit, opts: &FitOptions) -> Result<Report, String> {
    use rmpfit::MPFitter;
    let started = Instant::now();
    std::fs::create_dir_all(&opts.out)
        .map_err(|e| format!("{}: cannot create: {e}", opts.out.display()))?;
    let mut problem = Problem::new(fit, &opts.out, opts.jobs, fit.gradient, opts.quiet);
    let sensitive = problem.sensitive.clone();
    let mut z = vec![0.0; fit.params.len()];
    // The residuals at the start (cached for the algorithm's first evaluation): its first
    // step is bounded by `first_step` of their norm (z = 0 there, so MINPACK's bound
    // `factor · |D z|` is `factor` itself).
    let r0 = {
        let curves = problem
            .curves(&z)
            .map_err(|e| format!("at the start: {e}"))?;
        let mut r = vec![0.0; fit.data.len()];
        problem
            .deviates(&curves, &mut r)
            .map_err(|e| format!("at the start: {e}"))?;
        r.iter().map(|x| x * x).sum::<f64>().sqrt()
    };
    problem.config.step_factor = (fit.first_step * r0).max(1e-3);
    let status = problem.mpfit(&mut z);
    let status = status.map_err(|e| {
        let last = problem
            .history
            .iter()
            .rev()
            .find(|r| !r.status.is_empty())
            .map(|r| format!(": {}", r.status))
            .unwrap_or_default();
        format!("the fit stopped ({e:?}){last}")
    })?;
    let z: Vec<f64> = z
        .iter()
        .zip(&problem.pars)
        .map(|(z, p)| z.clamp(p.limit_low, p.limit_up))
        .collect();
    let values = problem.params_of(&z);
    let jac = problem.jacobian_at(&z)?;
    let curves = problem.curves(&z)?;
    let mut dev = vec![0.0; fit.data.len()];
    problem.deviates(&curves, &mut dev)?;
    let chi2: f64 = dev.iter().map(|r| r * r).sum();
    let (se_z, correlation, directions) = statistics(&fit.params, &jac);
    let parameters = fit
        .params
        .iter()
        .zip(&values)
        .zip(&se_z)
        .map(|((p, v), s)| {
            let tol = 1e-9 * (p.upper - p.lower);
            FittedParam {
                path: p.path.clone(),
                scale: p.scale,
                start: p.start,
                value: *v,
                lower: p.lower,
                upper: p.upper,
                standard_error: s * p.dp_dz(*v),
                standard_error_z: *s,
                at_bound: *v <= p.lower + tol || *v >= p.upper - tol,
            }
        })
        .collect();
    let chi2_start = problem.history.first().map_or(f64::NAN, |r| r.chi2);
    let m = fit.data.len();
    let dof = m.saturating_sub(fit.params.len());
    let undetermined = directions
        .iter()
        .filter(|d| d.standard_error > 1.0)
        .cloned()
        .collect();
    let report = Report {
        name: fit.name.clone(),
        fit_file: fit.file.display().to_string(),
        gradient: fit.gradient,
        case_gradients: fit
            .cases
            .iter()
            .zip(&sensitive)
            .map(|(c, s)| {
                let how = if *s {
                    "sensitivities (IDAS)".to_string()
                } else if fit.gradient == Gradient::Differences {
                    "central differences".to_string()
                } else {
                    format!("central differences ({})", restarts(&c.case).join("; "))
                };
                (c.name.clone(), how)
            })
            .collect(),
        termination: format!("{:?}", status.success),
        iterations: status.n_iter,
        evaluations: problem.history.len(),
        chi2_start,
        chi2,
        data_points: m,
        degrees_of_freedom: dof,
        reduced_chi2: if dof > 0 { chi2 / dof as f64 } else { f64::NAN },
        parameters,
        correlation,
        directions,
        undetermined,
        wall_seconds: started.elapsed().as_secs_f64(),
    };
    let json = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
    let path = opts.out.join("fit.json");
    std::fs::write(&path, json).map_err(|e| format!("{}: {e}", path.display()))?;
    // The data against the model at the start and at the fit.
    let z0 = vec![0.0; fit.params.len()];
    let start_curves = problem.curves(&z0).ok();
    write_residuals(&opts.out, fit, &curves, start_curves.as_deref())?;
    figures(&opts.out, fit, &curves, start_curves.as_deref())?;
    Ok(report)
}

fn write_residuals(
    out: &Path,
    fit: &Fit,
    curves: &[Curves],
    start: Option<&[Curves]>,
) -> Result<(), String> {
    let names = measure_names();
    let mut s = String::from("case,measure,t,value,sigma,weight,start,fitted,residual\n");
    for d in &fit.data {
        let fitted = curves[d.case].value(d.measure, d.when).unwrap_or(f64::NAN);
        let at_start = start
            .and_then(|c| c[d.case].value(d.measure, d.when).ok())
            .unwrap_or(f64::NAN);
        let t = curves[d.case].time(d.measure, d.when).unwrap_or(f64::NAN);
        s.push_str(&format!(
            "{},{},{t},{},{},{},{at_start},{fitted},{}\n",
            fit.cases[d.case].name,
            names[d.measure],
            d.value,
            d.sigma,
            d.weight,
            d.weight * (fitted - d.value) / d.sigma
        ));
    }
    let path = out.join("residuals.csv");
    std::fs::write(&path, s).map_err(|e| format!("{}: {e}", path.display()))
}

/// One figure per case and measure with data: the data (with ±σ bars), the model at the
/// start (dashed) and at the fit (solid).
fn figures(
    out: &Path,
    fit: &Fit,
    curves: &[Curves],
    start: Option<&[Curves]>,
) -> Result<(), String> {
    use crate::render::draw::{Curve, MarkShape, Marks, PALETTE, Stroke};
    use crate::render::time_plots::{TimePlot, time_figure};
    let names = measure_names();
    let mut pairs: Vec<(usize, usize)> = fit.data.iter().map(|d| (d.case, d.measure)).collect();
    pairs.sort_unstable();
    pairs.dedup();
    for (k, m) in pairs {
        let case = &fit.cases[k].case;
        let ph = &case.phases;
        let c = &curves[k];
        let line = |c: &Curves| -> Vec<(f64, f64)> {
            c.t.iter().zip(&c.values).map(|(t, v)| (*t, v[m])).collect()
        };
        let mut plot_curves = vec![Curve {
            label: "fitted".into(),
            points: line(c),
            color: PALETTE[0],
            stroke: Stroke::Solid,
        }];
        if let Some(s) = start {
            plot_curves.push(Curve {
                label: "start".into(),
                points: line(&s[k]),
                color: PALETTE[1],
                stroke: Stroke::Dashed,
            });
        }
        let data: Vec<&Datum> = fit
            .data
            .iter()
            .filter(|d| d.case == k && d.measure == m)
            .collect();
        let at = |d: &Datum| c.time(m, d.when).unwrap_or(ph.t_end);
        let plot = TimePlot {
            title: format!("{}: {} ({})", fit.name, names[m], fit.cases[k].name),
            y_desc: names[m].to_string(),
            curves: plot_curves,
            marks: vec![Marks {
                label: "data (±σ)".into(),
                points: data.iter().map(|d| (at(d), d.value)).collect(),
                color: PALETTE[2],
                radius: 3,
                filled: true,
                shape: MarkShape::Circle,
            }],
            links: data
                .iter()
                .map(|d| (at(d), d.value - d.sigma, d.value + d.sigma))
                .collect(),
            notes: Vec::new(),
            from_zero: false,
            phase_times: [ph.t_g0, ph.t_as0, ph.t_a0, ph.t_end],
            after_active: String::new(),
            t_max: ph.t_end,
            legend: plotters::prelude::SeriesLabelPosition::UpperLeft,
        };
        let path = out.join(format!("fit-{}-{}.png", fit.cases[k].name, names[m]));
        time_figure(&path, &plot).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

/// `cellsim fit FIT --make-data`: runs each Series target's case at `truth` (the other
/// parameters at their starts) and writes its data file: every output time after 0 and
/// each column of `noise`, the value plus Gaussian noise of that σ (seeded).
pub fn make_data(
    fit: &Fit,
    truth: &[(String, f64)],
    noise: &[(String, f64)],
    seed: u64,
    out: &Path,
) -> Result<Vec<PathBuf>, String> {
    let mut p: Vec<f64> = fit.params.iter().map(|q| q.start).collect();
    for (path, v) in truth {
        let j = fit
            .params
            .iter()
            .position(|q| &q.path == path)
            .ok_or_else(|| format!("--truth {path}: not a parameter of the fit"))?;
        let q = &fit.params[j];
        if !(*v >= q.lower && *v <= q.upper) {
            return Err(format!(
                "--truth {path} = {v}: outside its bounds [{}, {}]",
                q.lower, q.upper
            ));
        }
        p[j] = *v;
    }
    let names = measure_names();
    let cols = noise
        .iter()
        .map(|(c, s)| {
            let m = names
                .iter()
                .position(|n| n == c)
                .ok_or_else(|| format!("--noise {c}: not one of {}", names.join(", ")))?;
            if !(s.is_finite() && *s > 0.0) {
                return Err(format!("--noise {c} = {s}: σ must be > 0"));
            }
            Ok((m, *s))
        })
        .collect::<Result<Vec<_>, String>>()?;
    if cols.is_empty() {
        return Err("--noise: name at least one COLUMN=SIGMA".into());
    }
    if fit.series.is_empty() {
        return Err(format!(
            "{}: no Series target to write data for",
            fit.file.display()
        ));
    }
    let mut rng = crate::commands::sweep::design::SplitMix64(seed);
    let mut gauss = move || {
        // Box–Muller.
        let u1 = 1.0 - rng.unit();
        let u2 = rng.unit();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    };
    let mut written = Vec::new();
    for (k, path, _) in &fit.series {
        let dir = out.join("truth").join(&fit.cases[*k].name);
        let c = evaluate(fit, *k, &p, false, &dir)?;
        let mut s = format!("{}\n", spec::SERIES_HEADER);
        for (t, v) in c.t.iter().zip(&c.values) {
            for (m, sigma) in &cols {
                s.push_str(&format!(
                    "{t},{},{},{sigma}\n",
                    names[*m],
                    v[*m] + sigma * gauss()
                ));
            }
        }
        std::fs::write(path, s).map_err(|e| format!("{}: {e}", path.display()))?;
        written.push(path.clone());
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curves_interpolate_between_outputs_and_refuse_outside() {
        let c = Curves {
            t: vec![10.0, 20.0, 30.0],
            values: vec![vec![1.0], vec![3.0], vec![7.0]],
            derivatives: Some(vec![vec![vec![0.0], vec![2.0], vec![4.0]]]),
            t_end: 30.0,
        };
        assert_eq!(c.value(0, When::At(20.0)).unwrap(), 3.0);
        assert_eq!(c.value(0, When::At(25.0)).unwrap(), 5.0);
        assert_eq!(c.value(0, When::End).unwrap(), 7.0);
        assert_eq!(c.value(0, When::Lowest).unwrap(), 1.0);
        assert_eq!(c.time(0, When::Lowest).unwrap(), 10.0);
        assert_eq!(c.derivative(0, 0, When::At(15.0)).unwrap(), 1.0);
        assert!(c.value(0, When::At(5.0)).is_err());
        let short = Curves {
            t_end: 40.0,
            ..c.clone()
        };
        assert!(
            short
                .value(0, When::End)
                .unwrap_err()
                .contains("reached t = 30")
        );
        assert!(short.value(0, When::Lowest).is_ok());
    }

    #[test]
    fn statistics_of_a_linear_model_are_the_textbook_ones() {
        // Residuals r = (a + b tᵢ − dᵢ)/σ at t = 0, 1, 2, σ = 1: JᵀJ = [[3, 3], [3, 5]],
        // its inverse [[5, −3], [−3, 3]] / 6.
        let params: Vec<Param> = ["a", "b"]
            .iter()
            .map(|p| Param {
                path: p.to_string(),
                lower: -10.0,
                upper: 10.0,
                scale: Scale::Linear,
                start: 1.0,
                unit: 1.0,
                cases: vec![0],
            })
            .collect();
        let jac = vec![vec![1.0, 0.0], vec![1.0, 1.0], vec![1.0, 2.0]];
        let (se, corr, dirs) = statistics(&params, &jac);
        assert!((se[0] - (5.0f64 / 6.0).sqrt()).abs() < 1e-12);
        assert!((se[1] - (3.0f64 / 6.0).sqrt()).abs() < 1e-12);
        let c01 = -3.0 / 6.0 / ((5.0f64 / 6.0).sqrt() * (3.0f64 / 6.0).sqrt());
        assert!((corr[0][1] - c01).abs() < 1e-12);
        assert!(dirs[0].singular_value >= dirs[1].singular_value);
        // The eigenvalues of JᵀJ are 4 ± √10.
        let s2: Vec<f64> = dirs.iter().map(|d| d.singular_value.powi(2)).collect();
        assert!((s2[0] - (4.0 + 10f64.sqrt())).abs() < 1e-10);
        assert!((s2[1] - (4.0 - 10f64.sqrt())).abs() < 1e-10);
    }
}
