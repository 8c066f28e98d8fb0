//! `cellsim sweep`: many runs of one base case, each with some fields changed by
//! `--set`-style overrides ([`crate::case::overrides`]), in parallel, resumable, into
//! `DIR/points/<id>/`, with one table (`sweep.csv`) and figures drawn from it.
//!
//! A sweep file:
//!
//! ```ron
//! (
//!     name: "pillar-geometry",
//!     base: "../pillars-push-pull.ron",          // relative to the sweep file
//!     design: Grid([                             // see design.rs for the four designs
//!         (path: "substrate.width",   values: Range(start: 4.0, stop: 12.0, n: 5)),
//!         (path: "substrate.spacing", values: [4.0, 6.0, 8.0, 10.0, 12.0]),
//!     ]),
//!     set: ["solver.rtol=1e-3"],                 // applied to every point (optional)
//!     derive: [                                  // fields computed from others (optional)
//!         (path: "substrate.first_center", expr: "(substrate.width + substrate.spacing) / 2"),
//!     ],
//! )
//! ```
//!
//! Each point's case is the base with `set`, then the point's axis values, then the
//! derived fields applied, validated as a case file is. A point whose case breaks a rule
//! of the schema is *invalid*: reported with its message, not run. An override that does
//! not apply at all (an unknown field, a value of the wrong type) stops the sweep before
//! anything runs.
//!
//! `DIR/points/<id>/` holds `case.ron` (the resolved case, as `cellsim check` prints it)
//! and the run's usual files, or `invalid.txt` (the validation message), or `error.txt`
//! (a run that could not start). `DIR/sweep.json` records the design and the settings,
//! `DIR/sweep.csv` the results ([`table`]). Running the same sweep again skips the points
//! whose `case.ron` is unchanged and whose summary says finished (or failed, unless
//! `retry_failed`); `--shard i/K` runs the points k with k mod K = i only, and
//! [`collect`] assembles the table and figures from the point directories.

pub mod compare;
pub mod design;
pub mod plots;
pub mod slurm;
pub mod table;

use std::collections::VecDeque;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};

use crate::case::overrides::{self, value_at};
use crate::case::{Case, CaseError, Override, Substrate};
use crate::output::OutputError;
use crate::record::{FailureKind, RunSettings};
use crate::run::{self, Progress, RunError, RunOptions};
use crate::stop::StopFlag;

pub use compare::TableSpec;
pub use design::{Design, DesignSpec, Kind};
pub use table::{Row, Status};

/// Why a sweep could not be set up, run or collected.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// Bad input: the sweep file, its base case, an override, a command-line value.
    #[error("{0}")]
    Input(String),
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// A figure could not be drawn or written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// `sbatch` failed.
    #[error("{0}")]
    Submit(String),
}

impl SweepError {
    fn io(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
        move |source| SweepError::Io {
            path: path.display().to_string(),
            source,
        }
    }

    /// Whether the error is bad input (exit status 2) rather than a failure to write.
    pub fn is_input(&self) -> bool {
        matches!(self, SweepError::Input(_))
    }
}

/// A field computed from others for every point: `expr` is arithmetic (`+ - * /`,
/// parentheses, numbers) over dotted paths of the point's case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Derived {
    /// Dotted path of the field set.
    pub path: String,
    /// The expression, e.g. `(substrate.width + substrate.spacing) / 2`.
    pub expr: String,
}

/// The sweep file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// Name of the sweep.
    pub name: String,
    /// The base case, relative to the sweep file.
    pub base: String,
    /// The points.
    pub design: DesignSpec,
    /// Overrides applied to every point (`PATH=VALUE`).
    #[serde(default)]
    pub set: Vec<String>,
    /// Fields computed from others for every point.
    #[serde(default)]
    pub derive: Vec<Derived>,
    /// The comparison table ([`compare`]), for a Grid of two axes.
    #[serde(default, deserialize_with = "present_table")]
    pub table: Option<TableSpec>,
}

fn present_table<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<TableSpec>, D::Error> {
    TableSpec::deserialize(d).map(Some)
}

/// One point, resolved.
#[derive(Debug, Clone)]
pub struct Point {
    /// Id and directory name.
    pub id: String,
    /// Its value on each axis (RON text; the base's for an axis it does not set).
    pub values: Vec<String>,
    /// All overrides applied to the base: `set`, the axis values, the derived fields.
    pub overrides: Vec<Override>,
    /// The resolved case and its text (`case.ron`), or the validation message.
    pub case: Result<(Case, String), String>,
}

/// RON text on one line: every run of whitespace (line breaks included) made one space.
fn single_line(ron: &str) -> String {
    ron.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// A sweep file with its points resolved.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Name of the sweep.
    pub name: String,
    /// The sweep file.
    pub sweep_file: PathBuf,
    /// The base case file.
    pub base: PathBuf,
    /// The design.
    pub design: Design,
    /// Overrides of every point.
    pub set: Vec<Override>,
    /// Derived fields.
    pub derive: Vec<Derived>,
    /// The comparison table, its documents' paths resolved.
    pub table: Option<TableSpec>,
    /// The points, in design order.
    pub points: Vec<Point>,
}

/// `sweep.json`: what was swept and how; enough for `collect` and `plot`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Name of the sweep.
    pub name: String,
    /// The sweep file, as given.
    pub sweep_file: String,
    /// The base case file.
    pub base: String,
    /// The design with its values.
    pub design: Design,
    /// Overrides of every point.
    pub set: Vec<String>,
    /// Derived fields.
    pub derive: Vec<Derived>,
    /// The points: id, value on each axis, overrides applied.
    pub points: Vec<RecordPoint>,
    /// Settings of the command that wrote the record.
    pub settings: Settings,
    /// cellsim version.
    pub cellsim_version: String,
    /// The comparison table, if the sweep file has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<TableSpec>,
}

/// A point in `sweep.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordPoint {
    /// Id.
    pub id: String,
    /// Value on each axis.
    pub values: Vec<String>,
    /// Overrides applied to the base, `PATH=VALUE`.
    pub overrides: Vec<String>,
}

/// Settings of a sweep command.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Runs at once.
    pub jobs: usize,
    /// Rerun failed points.
    pub retry_failed: bool,
    /// Wall-clock budget of each run [s].
    pub max_wall: Option<f64>,
    /// Number of shards, when sharded.
    pub shards: Option<usize>,
}

impl Record {
    /// The axis paths.
    pub fn axes(&self) -> Vec<String> {
        self.design.axes.iter().map(|a| a.path.clone()).collect()
    }

    /// Reads `DIR/sweep.json`.
    pub fn load(dir: &Path) -> Result<Record, SweepError> {
        let path = dir.join("sweep.json");
        let text = std::fs::read_to_string(&path).map_err(|e| {
            SweepError::Input(format!(
                "{}: {e} (not a sweep directory: `cellsim sweep SWEEP.ron --out DIR` writes it)",
                path.display()
            ))
        })?;
        serde_json::from_str(&text)
            .map_err(|e| SweepError::Input(format!("{}: {e}", path.display())))
    }
}

// ---------------------------------------------------------------------------------------
// Loading a sweep file

fn located(file: &Path, e: &ron::error::SpannedError) -> String {
    format!(
        "{}:{}:{}: {}",
        file.display(),
        e.span.start.line,
        e.span.start.col,
        e.code
    )
}

/// A number from RON text: `1.5`, `Some(1.5)`.
fn parse_number(text: &str) -> Option<f64> {
    let t = text.trim();
    let t = t
        .strip_prefix("Some(")
        .and_then(|s| s.strip_suffix(')'))
        .unwrap_or(t);
    t.trim().parse().ok()
}

/// Evaluates `expr` with `lookup` giving the value of a dotted path.
fn eval(expr: &str, lookup: &dyn Fn(&str) -> Option<f64>) -> Result<f64, String> {
    struct P<'a> {
        s: &'a [u8],
        i: usize,
        lookup: &'a dyn Fn(&str) -> Option<f64>,
    }
    impl P<'_> {
        fn ws(&mut self) {
            while self.s.get(self.i).is_some_and(|c| c.is_ascii_whitespace()) {
                self.i += 1;
            }
        }
        fn peek(&mut self) -> Option<u8> {
            self.ws();
            self.s.get(self.i).copied()
        }
        fn sum(&mut self, depth: usize) -> Result<f64, String> {
            let mut v = self.product(depth)?;
            while let Some(c @ (b'+' | b'-')) = self.peek() {
                self.i += 1;
                let w = self.product(depth)?;
                v = if c == b'+' { v + w } else { v - w };
            }
            Ok(v)
        }
        fn product(&mut self, depth: usize) -> Result<f64, String> {
            let mut v = self.atom(depth)?;
            while let Some(c @ (b'*' | b'/')) = self.peek() {
                self.i += 1;
                let w = self.atom(depth)?;
                v = if c == b'*' { v * w } else { v / w };
            }
            Ok(v)
        }
        fn atom(&mut self, depth: usize) -> Result<f64, String> {
            if depth > 32 {
                return Err("nested too deeply".into());
            }
            match self.peek() {
                Some(b'-') => {
                    self.i += 1;
                    Ok(-self.atom(depth + 1)?)
                }
                Some(b'(') => {
                    self.i += 1;
                    let v = self.sum(depth + 1)?;
                    if self.peek() != Some(b')') {
                        return Err(format!("expected `)` at character {}", self.i + 1));
                    }
                    self.i += 1;
                    Ok(v)
                }
                Some(c) if c.is_ascii_digit() || c == b'.' => {
                    let start = self.i;
                    while self.s.get(self.i).is_some_and(|&c| {
                        c.is_ascii_digit()
                            || c == b'.'
                            || c == b'e'
                            || c == b'E'
                            || ((c == b'-' || c == b'+')
                                && matches!(self.s[self.i - 1], b'e' | b'E'))
                    }) {
                        self.i += 1;
                    }
                    let t = String::from_utf8_lossy(&self.s[start..self.i]);
                    t.parse().map_err(|_| format!("`{t}` is not a number"))
                }
                Some(c) if c.is_ascii_alphabetic() || c == b'_' => {
                    let start = self.i;
                    while self
                        .s
                        .get(self.i)
                        .is_some_and(|&c| c.is_ascii_alphanumeric() || c == b'_' || c == b'.')
                    {
                        self.i += 1;
                    }
                    let path = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                    (self.lookup)(&path)
                        .ok_or_else(|| format!("`{path}` is not a numeric field of the case"))
                }
                Some(c) => Err(format!(
                    "unexpected `{}` at character {}",
                    c as char,
                    self.i + 1
                )),
                None => Err("unexpected end of the expression".into()),
            }
        }
    }
    let mut p = P {
        s: expr.as_bytes(),
        i: 0,
        lookup,
    };
    let v = p.sum(0)?;
    if p.peek().is_some() {
        return Err(format!("unexpected text at character {}", p.i + 1));
    }
    if !v.is_finite() {
        return Err(format!("the value is {v}"));
    }
    Ok(v)
}

impl Plan {
    /// Reads the sweep file and its base case and resolves every point. Errors name the
    /// file (and line and column where ron tells them) or the axis.
    pub fn load(sweep_file: &Path) -> Result<Plan, SweepError> {
        let text = std::fs::read_to_string(sweep_file).map_err(|e| {
            SweepError::Input(format!(
                "{}: cannot read the sweep file: {e}",
                sweep_file.display()
            ))
        })?;
        let spec: SweepFile = ron::Options::default()
            .from_str(text.trim_start_matches('\u{FEFF}'))
            .map_err(|e| SweepError::Input(located(sweep_file, &e)))?;
        let bad = |m: String| SweepError::Input(format!("{}: {m}", sweep_file.display()));
        let name_ok = !spec.name.is_empty()
            && !spec.name.contains(['/', '\\'])
            && spec.name != "."
            && spec.name != ".."
            && !spec.name.chars().any(char::is_control);
        if !name_ok {
            return Err(bad(format!(
                "name = {:?} is not allowed (a single path component, not empty)",
                spec.name
            )));
        }
        let base = sweep_file
            .parent()
            .unwrap_or(Path::new("."))
            .join(&spec.base);
        let base_text = std::fs::read(&base).map_err(|e| {
            bad(format!(
                "base = {:?}: cannot read {}: {e}",
                spec.base,
                base.display()
            ))
        })?;
        let base_text = String::from_utf8(base_text).map_err(|_| {
            bad(format!(
                "base = {:?}: {} is not UTF-8 text",
                spec.base,
                base.display()
            ))
        })?;
        let base_label = base.display().to_string();
        let set: Vec<Override> = spec
            .set
            .iter()
            .map(|s| {
                Override::parse(s)
                    .map(|o| o.from_source(format!("sweep set `{s}`")))
                    .map_err(|m| bad(format!("set: {m}")))
            })
            .collect::<Result<_, _>>()?;
        let design = Design::from_spec(&spec.design).map_err(|m| bad(format!("design: {m}")))?;
        for d in &spec.derive {
            Override::new(&d.path, "0").map_err(|m| bad(format!("derive: {m}")))?;
        }
        let table = spec
            .table
            .clone()
            .map(|t| {
                t.resolve(
                    &design,
                    &spec.name,
                    sweep_file.parent().unwrap_or(Path::new(".")),
                )
            })
            .transpose()
            .map_err(bad)?;

        // The base alone (with `set`): the values of axes a point leaves alone, and the
        // defaults derived expressions may read.
        let base_case = Case::from_str_with_overrides(&base_text, &base_label, &set)
            .ok()
            .and_then(|c| c.to_ron().ok());
        let defaults = Case::new("defaults", Substrate::pillars(), 1.0)
            .to_ron()
            .unwrap_or_default();

        let mut points = Vec::new();
        for dp in design.points() {
            let mut ovs = set.clone();
            for (axis, v) in design.axes.iter().zip(&dp.values) {
                let Some(v) = v else { continue };
                if let Some(set) = axis.variant_set(v) {
                    for o in set {
                        let origin = format!("sweep axis `{}`, variant `{v}`: `{o}`", axis.path);
                        ovs.push(Override::parse(o).map(|o| o.from_source(origin)).map_err(
                            |m| bad(format!("design: axis `{}`: variant `{v}`: {m}", axis.path)),
                        )?);
                    }
                } else {
                    let o = Override::new(&axis.path, v)
                        .map_err(|m| bad(format!("design: axis `{}`: value {m}", axis.path)))?;
                    ovs.push(o.from_source(format!("sweep axis `{}` = {v}", axis.path)));
                }
            }
            for d in &spec.derive {
                let written = overrides::apply(&base_text, &ovs).ok().map(|e| e.text);
                let lookup = |path: &str| -> Option<f64> {
                    if let Some(o) = ovs.iter().rev().find(|o| o.path == path) {
                        return parse_number(&o.value);
                    }
                    written
                        .as_deref()
                        .and_then(|t| value_at(t, path))
                        .or_else(|| value_at(&defaults, path))
                        .and_then(|v| parse_number(&v))
                };
                let v = eval(&d.expr, &lookup).map_err(|m| {
                    bad(format!(
                        "derive `{}` = `{}` at point {}: {m}",
                        d.path, d.expr, dp.id
                    ))
                })?;
                let value = design::fmt_number(v);
                let origin = format!("sweep derive `{}` = `{}` = {value}", d.path, d.expr);
                ovs.push(
                    Override::new(&d.path, &value)
                        .map_err(|m| bad(format!("derive: {m}")))?
                        .from_source(origin),
                );
            }
            let case = match Case::from_str_with_overrides(&base_text, &base_label, &ovs) {
                Ok(c) => {
                    let text = c
                        .to_ron()
                        .map_err(|e| bad(format!("point {}: {e}", dp.id)))?;
                    Ok((c, text))
                }
                Err(e @ CaseError::Invalid { .. }) => Err(e.to_string()),
                Err(e) => {
                    return Err(SweepError::Input(format!(
                        "{}: point {}: {e}",
                        sweep_file.display(),
                        dp.id
                    )));
                }
            };
            // On one line: a struct value (a whole `active.pac`) is written over several
            // lines in a case, and sweep.csv holds one point per line.
            let values = design
                .axes
                .iter()
                .zip(&dp.values)
                .map(|(a, v)| match v {
                    Some(v) => single_line(v),
                    // A variant axis left alone: the base as it is.
                    None if a.is_variants() => "(base)".to_string(),
                    None => base_case
                        .as_deref()
                        .and_then(|t| value_at(t, &a.path))
                        .map(|v| single_line(&v))
                        .unwrap_or_default(),
                })
                .collect();
            points.push(Point {
                id: dp.id,
                values,
                overrides: ovs,
                case,
            });
        }
        // One at a time: a value equal to the base's gives the base point again.
        if design.kind == Kind::OneAtATime {
            let base_text_resolved = points
                .first()
                .and_then(|p| p.case.as_ref().ok())
                .map(|(_, t)| t.clone());
            if let Some(b) = base_text_resolved {
                let mut first = true;
                points.retain(|p| {
                    let keep = first || p.case.as_ref().map_or(true, |(_, t)| *t != b);
                    first = false;
                    keep
                });
            }
        }
        Ok(Plan {
            name: spec.name,
            sweep_file: sweep_file.to_path_buf(),
            base,
            design,
            set,
            derive: spec.derive,
            table,
            points,
        })
    }

    /// The record written to `sweep.json`.
    pub fn record(&self, settings: Settings) -> Record {
        Record {
            name: self.name.clone(),
            sweep_file: self.sweep_file.display().to_string(),
            base: self.base.display().to_string(),
            design: self.design.clone(),
            set: self.set.iter().map(Override::to_string).collect(),
            derive: self.derive.clone(),
            points: self
                .points
                .iter()
                .map(|p| RecordPoint {
                    id: p.id.clone(),
                    values: p.values.clone(),
                    overrides: p.overrides.iter().map(Override::to_string).collect(),
                })
                .collect(),
            settings,
            cellsim_version: env!("CARGO_PKG_VERSION").to_string(),
            table: self.table.clone(),
        }
    }
}

// ---------------------------------------------------------------------------------------
// Point directories

/// Writes `text` to `path` through a temporary file (named for this process, so that
/// shards writing the same file do not collide) and a rename.
fn write_atomic(path: &Path, text: &str) -> Result<(), SweepError> {
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    std::fs::write(&tmp, text).map_err(SweepError::io(&tmp))?;
    std::fs::rename(&tmp, path).map_err(SweepError::io(path))
}

/// The row of a point from the files in its directory.
pub fn read_row(id: &str, values: &[String], dir: &Path) -> Row {
    let values = values.to_vec();
    let read = |name: &str| std::fs::read_to_string(dir.join(name)).ok();
    if let Some(msg) = read("invalid.txt") {
        return Row::bare(id, values, Status::Invalid, &msg);
    }
    let Some(case_text) = read("case.ron") else {
        return Row::bare(id, values, Status::Missing, "not run");
    };
    let summary = crate::record::read::read_summary(dir);
    let s = match summary {
        Ok(s) => s,
        // A summary that does not read (e.g. one of an older cellsim): the point is run
        // again by the next `cellsim sweep`, as one without a summary.
        Err(e) if dir.join("summary.json").exists() => {
            return Row::bare(id, values, Status::Missing, &e.to_string());
        }
        Err(_) => {
            return match read("error.txt") {
                Some(msg) => Row::bare(id, values, Status::Failed, &msg),
                None => Row::bare(
                    id,
                    values,
                    Status::Missing,
                    "no summary.json: not run or still running",
                ),
            };
        }
    };
    let (status, reason) = if s.finished {
        (Status::Finished, String::new())
    } else {
        match &s.failure {
            Some(f) if f.kind == FailureKind::Interrupted => {
                (Status::Interrupted, f.reason.clone())
            }
            Some(f) => (Status::Failed, f.reason.clone()),
            None => (
                Status::Interrupted,
                "the run ended without a summary of why (killed?)".to_string(),
            ),
        }
    };
    let case = Case::from_str(&case_text, &dir.join("case.ron").display().to_string()).ok();
    let penetration = match (&case, &s.final_values) {
        (Some(c), Some(o)) => Some(table::penetration_depth(c, o.uy_bottom)),
        _ => None,
    };
    Row {
        id: id.to_string(),
        values,
        status,
        last: s.final_values,
        penetration,
        wall_seconds: Some(s.wall_seconds + s.setup_seconds),
        steps: Some(s.stats.steps),
        reason: table::one_line(&reason),
    }
}

/// Whether a point's directory holds a run of `text` that need not run again.
fn is_done(dir: &Path, text: &str, retry_failed: bool) -> bool {
    if std::fs::read_to_string(dir.join("case.ron"))
        .ok()
        .as_deref()
        != Some(text)
    {
        return false;
    }
    match crate::record::read::read_summary(dir) {
        Ok(s) if s.finished => true,
        Ok(s) => match s.failure {
            Some(f) if f.kind != FailureKind::Interrupted => !retry_failed,
            _ => false,
        },
        Err(_) => dir.join("error.txt").exists() && !retry_failed,
    }
}

/// Empties a point's directory and writes `name` into it.
fn reset_point_dir(dir: &Path, name: &str, text: &str) -> Result<(), SweepError> {
    if dir.exists() {
        std::fs::remove_dir_all(dir).map_err(SweepError::io(dir))?;
    }
    std::fs::create_dir_all(dir).map_err(SweepError::io(dir))?;
    write_atomic(&dir.join(name), text)
}

// ---------------------------------------------------------------------------------------
// Running

/// Options of [`run_sweep`].
#[derive(Debug, Clone)]
pub struct SweepOptions {
    /// Output directory.
    pub out: PathBuf,
    /// Runs at once.
    pub jobs: usize,
    /// Rerun points that failed.
    pub retry_failed: bool,
    /// Only the points of shard `i` of `K` (k mod K = i).
    pub shard: Option<(usize, usize)>,
    /// Wall-clock budget of each run [s].
    pub max_wall: Option<f64>,
    /// Show progress (a bar on a terminal, a line per point otherwise).
    pub progress: bool,
    /// Set to stop every run cleanly.
    pub interrupt: StopFlag,
}

/// What a sweep did.
#[derive(Debug, Clone)]
pub struct SweepReport {
    /// The rows of the points of this command (all, or the shard's), in design order.
    pub rows: Vec<Row>,
    /// Points run by this command.
    pub ran: usize,
    /// Points skipped because their run was already there.
    pub reused: usize,
    /// Points not run because their case is another point's: that point's directory
    /// copied.
    pub copied: usize,
    /// Files written besides the point directories (sweep.csv, figures).
    pub written: Vec<PathBuf>,
    /// Wall time of the whole command [s].
    pub wall_seconds: f64,
}

impl SweepReport {
    /// Count of rows with `status`.
    pub fn count(&self, status: Status) -> usize {
        self.rows.iter().filter(|r| r.status == status).count()
    }

    /// One line: the counts by status.
    pub fn counts(&self) -> String {
        counts(&self.rows)
    }
}

/// "N points: a finished, b failed, ..." for `rows`.
pub fn counts(rows: &[Row]) -> String {
    let n = |s: Status| rows.iter().filter(|r| r.status == s).count();
    format!(
        "{} points: {} finished, {} failed, {} invalid, {} interrupted, {} missing",
        rows.len(),
        n(Status::Finished),
        n(Status::Failed),
        n(Status::Invalid),
        n(Status::Interrupted),
        n(Status::Missing)
    )
}

/// Whether point number `k` belongs to the shard.
fn in_shard(k: usize, shard: Option<(usize, usize)>) -> bool {
    shard.is_none_or(|(i, n)| k % n == i)
}

/// Parses `i/K` (0 ≤ i < K).
pub fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let err = || format!("--shard `{s}` is not i/K with 0 <= i < K (e.g. 0/4)");
    let (i, k) = s.split_once('/').ok_or_else(err)?;
    let (i, k): (usize, usize) = (
        i.trim().parse().map_err(|_| err())?,
        k.trim().parse().map_err(|_| err())?,
    );
    if k == 0 || i >= k {
        return Err(err());
    }
    Ok((i, k))
}

struct Shared {
    csv: Option<std::fs::File>,
    rows: Vec<Option<Row>>,
    done: usize,
    failed: usize,
    copied: usize,
}

/// Runs the plan's points (those of the shard) into `opts.out`; see the module
/// documentation.
pub fn run_sweep(plan: &Plan, opts: &SweepOptions) -> Result<SweepReport, SweepError> {
    let start = Instant::now();
    let out = &opts.out;
    let points_dir = out.join("points");
    std::fs::create_dir_all(&points_dir).map_err(SweepError::io(&points_dir))?;
    let record = plan.record(Settings {
        jobs: opts.jobs,
        retry_failed: opts.retry_failed,
        max_wall: opts.max_wall,
        shards: opts.shard.map(|(_, k)| k),
    });
    let json = serde_json::to_string_pretty(&record).map_err(|e| SweepError::Io {
        path: out.join("sweep.json").display().to_string(),
        source: std::io::Error::other(e),
    })?;
    write_atomic(&out.join("sweep.json"), &json)?;
    let axes = record.axes();

    // What each point of this command needs.
    let mine: Vec<usize> = (0..plan.points.len())
        .filter(|&k| in_shard(k, opts.shard))
        .collect();
    let mut rows: Vec<Option<Row>> = vec![None; plan.points.len()];
    let mut queue = VecDeque::new();
    let mut reused = 0;
    // A point whose resolved case is an earlier point's is not run again: it gets a copy
    // of that point's directory (runs are deterministic), e.g. a reading that leaves one
    // of the scenes of a variant axis unchanged.
    let mut first_with: std::collections::HashMap<&str, usize> = Default::default();
    let mut copies: std::collections::HashMap<usize, Vec<usize>> = Default::default();
    for &k in &mine {
        let p = &plan.points[k];
        let dir = points_dir.join(&p.id);
        match &p.case {
            Err(msg) => {
                if std::fs::read_to_string(dir.join("invalid.txt"))
                    .ok()
                    .as_deref()
                    != Some(msg.as_str())
                {
                    reset_point_dir(&dir, "invalid.txt", msg)?;
                }
                rows[k] = Some(read_row(&p.id, &p.values, &dir));
            }
            Ok((_, text)) if is_done(&dir, text, opts.retry_failed) => {
                reused += 1;
                rows[k] = Some(read_row(&p.id, &p.values, &dir));
                first_with.entry(text).or_insert(k);
            }
            Ok((_, text)) => match first_with.get(text.as_str()) {
                Some(&j) => copies.entry(j).or_default().push(k),
                None => {
                    first_with.insert(text, k);
                    queue.push_back(k);
                }
            },
        }
    }
    // Copies of points already done are made now.
    let mut copied = 0;
    for (j, ks) in copies.iter_mut() {
        if rows[*j].is_some() {
            for &k in ks.iter() {
                let p = &plan.points[k];
                let dir = points_dir.join(&p.id);
                copy_point(&points_dir.join(&plan.points[*j].id), &dir)?;
                rows[k] = Some(read_row(&p.id, &p.values, &dir));
                copied += 1;
            }
            ks.clear();
        }
    }
    let to_copy: usize = copies.values().map(Vec::len).sum();
    let to_run = queue.len();
    let total = to_run + to_copy;

    // sweep.csv as points finish (not when sharded: shards share the directory).
    let csv_path = out.join("sweep.csv");
    let csv = if opts.shard.is_none() {
        let mut f = std::fs::File::create(&csv_path).map_err(SweepError::io(&csv_path))?;
        let mut text = table::header(&axes) + "\n";
        for r in rows.iter().flatten() {
            text += &(table::line(r) + "\n");
        }
        f.write_all(text.as_bytes())
            .map_err(SweepError::io(&csv_path))?;
        Some(f)
    } else {
        None
    };

    let visible = opts.progress && std::io::stderr().is_terminal();
    let bar = if visible {
        let pb = ProgressBar::new(total as u64);
        let style = ProgressStyle::with_template(
            "{prefix} [{bar:30}] {pos}/{len} points {msg}, {elapsed} elapsed, ETA {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
        pb.set_style(style);
        pb.set_prefix(plan.name.clone());
        pb.set_message("(0 failed)");
        pb
    } else {
        ProgressBar::hidden()
    };
    if opts.progress {
        let msg = format!(
            "{}: {} points{}: {} to run, {} reused, {} invalid{}; {} at once",
            plan.name,
            mine.len(),
            opts.shard
                .map(|(i, k)| format!(" in shard {i}/{k}"))
                .unwrap_or_default(),
            to_run,
            reused,
            mine.len() - total - reused - copied,
            if to_copy + copied > 0 {
                format!(
                    ", {} the same case as another point (copied)",
                    to_copy + copied
                )
            } else {
                String::new()
            },
            opts.jobs.min(to_run.max(1))
        );
        if visible {
            bar.println(msg);
        } else {
            let _ = writeln!(std::io::stderr(), "{msg}");
        }
    }

    let shared = Mutex::new(Shared {
        csv,
        rows,
        done: 0,
        failed: 0,
        copied,
    });
    let queue = Mutex::new(queue);
    let jobs = opts.jobs.clamp(1, to_run.max(1));
    let first_error: Mutex<Option<SweepError>> = Mutex::new(None);
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| {
                loop {
                    if opts.interrupt.is_set() {
                        break;
                    }
                    let next = queue.lock().ok().and_then(|mut q| q.pop_front());
                    let Some(k) = next else { break };
                    let p = &plan.points[k];
                    let dir = points_dir.join(&p.id);
                    let t0 = Instant::now();
                    let row = match run_point(p, &dir, opts) {
                        Ok(row) => row,
                        Err(e) => {
                            if let Ok(mut f) = first_error.lock() {
                                f.get_or_insert(e);
                            }
                            break;
                        }
                    };
                    let wall = t0.elapsed().as_secs_f64();
                    let mut done = vec![(k, row, None)];
                    // Its copies, unless it was interrupted (then they run later).
                    if done[0].1.status != Status::Interrupted {
                        for &c in copies.get(&k).into_iter().flatten() {
                            let q = &plan.points[c];
                            let cdir = points_dir.join(&q.id);
                            match copy_point(&dir, &cdir) {
                                Ok(()) => done.push((
                                    c,
                                    read_row(&q.id, &q.values, &cdir),
                                    Some(p.id.as_str()),
                                )),
                                Err(e) => {
                                    if let Ok(mut f) = first_error.lock() {
                                        f.get_or_insert(e);
                                    }
                                }
                            }
                        }
                    }
                    let Ok(mut sh) = shared.lock() else { break };
                    for (k, row, copy_of) in done {
                        sh.done += 1;
                        sh.copied += usize::from(copy_of.is_some());
                        if row.status == Status::Failed {
                            sh.failed += 1;
                        }
                        if let Some(f) = sh.csv.as_mut() {
                            let _ = f
                                .write_all((table::line(&row) + "\n").as_bytes())
                                .and_then(|_| f.flush());
                        }
                        let line = match copy_of {
                            None => point_line(&row, &axes, sh.done, total, wall),
                            Some(of) => copy_line(&row, &axes, sh.done, total, of),
                        };
                        if visible {
                            bar.inc(1);
                            bar.set_message(format!("({} failed)", sh.failed));
                            if row.status != Status::Finished {
                                bar.println(line);
                            }
                        } else if opts.progress {
                            let _ = writeln!(std::io::stderr(), "{line}");
                        }
                        sh.rows[k] = Some(row);
                    }
                }
            });
        }
    });
    bar.finish_and_clear();
    if let Some(e) = first_error.into_inner().ok().flatten() {
        return Err(e);
    }
    let (rows, copied) = shared
        .into_inner()
        .map(|s| (s.rows, s.copied))
        .unwrap_or_default();
    let rows: Vec<Row> = mine
        .iter()
        .map(|&k| {
            let p = &plan.points[k];
            rows[k]
                .clone()
                .unwrap_or_else(|| read_row(&p.id, &p.values, &points_dir.join(&p.id)))
        })
        .collect();
    let mut written = Vec::new();
    if opts.shard.is_none() {
        write_atomic(&csv_path, &table::render(&axes, &rows))?;
        written.push(csv_path);
        written.extend(plots::draw(out, &record, &rows, None)?);
        written.extend(compare::write(out, &record, &rows)?);
    }
    Ok(SweepReport {
        rows,
        ran: to_run,
        reused,
        copied,
        written,
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

/// The log line of a finished point.
fn point_line(row: &Row, axes: &[String], n: usize, total: usize, wall: f64) -> String {
    let at: Vec<String> = axes
        .iter()
        .zip(&row.values)
        .map(|(a, v)| format!("{a}={v}"))
        .collect();
    let detail = match row.status {
        Status::Finished => format!(
            "uy_top {:.4} µm, penetration {:.3} µm",
            row.quantity("uy_top").unwrap_or(f64::NAN),
            row.penetration.unwrap_or(f64::NAN)
        ),
        _ => row.reason.clone(),
    };
    format!(
        "[{n}/{total}] {} {} in {wall:.1} s ({}): {detail}",
        row.id,
        row.status.as_str(),
        at.join(", ")
    )
}

/// The log line of a point copied from point `of`.
fn copy_line(row: &Row, axes: &[String], n: usize, total: usize, of: &str) -> String {
    let at: Vec<String> = axes
        .iter()
        .zip(&row.values)
        .map(|(a, v)| format!("{a}={v}"))
        .collect();
    format!(
        "[{n}/{total}] {} {}: the same case as {of}, copied ({})",
        row.id,
        row.status.as_str(),
        at.join(", ")
    )
}

/// Makes `to` a copy of point directory `from` (emptied first; files and folders).
fn copy_point(from: &Path, to: &Path) -> Result<(), SweepError> {
    fn copy_dir(from: &Path, to: &Path) -> Result<(), SweepError> {
        std::fs::create_dir_all(to).map_err(SweepError::io(to))?;
        for entry in std::fs::read_dir(from).map_err(SweepError::io(from))? {
            let entry = entry.map_err(SweepError::io(from))?;
            let (src, dst) = (entry.path(), to.join(entry.file_name()));
            if entry.file_type().map_err(SweepError::io(&src))?.is_dir() {
                copy_dir(&src, &dst)?;
            } else {
                std::fs::copy(&src, &dst).map_err(SweepError::io(&src))?;
            }
        }
        Ok(())
    }
    if to.exists() {
        std::fs::remove_dir_all(to).map_err(SweepError::io(to))?;
    }
    copy_dir(from, to)
}

/// Runs one point into `dir` (emptied first) and reads its row back.
fn run_point(p: &Point, dir: &Path, opts: &SweepOptions) -> Result<Row, SweepError> {
    let Ok((case, text)) = &p.case else {
        return Ok(read_row(&p.id, &p.values, dir));
    };
    reset_point_dir(dir, "case.ron", text)?;
    let mut settings = RunSettings::from_case(case);
    settings.max_wall_seconds = opts.max_wall;
    let ropts = RunOptions {
        out: dir.to_path_buf(),
        settings,
        progress: Progress::Hidden,
        interrupt: opts.interrupt.clone(),
        snapshots: Default::default(),
    };
    let label = dir.join("case.ron").display().to_string();
    match run::run(case, &label, &ropts) {
        Ok(_) | Err(RunError::Integration { .. }) => {}
        // The case is one the model cannot take: as invalid as a rule broken.
        Err(e @ (RunError::Scene(_) | RunError::Mesh { .. })) => {
            reset_point_dir(dir, "invalid.txt", &e.to_string())?;
        }
        Err(e) => {
            if !dir.join("summary.json").exists() {
                write_atomic(&dir.join("error.txt"), &e.to_string())?;
            }
        }
    }
    Ok(read_row(&p.id, &p.values, dir))
}

// ---------------------------------------------------------------------------------------
// Collect and plot

/// What [`collect`] found.
#[derive(Debug, Clone)]
pub struct Collected {
    /// Every point's row, in design order.
    pub rows: Vec<Row>,
    /// Files written.
    pub written: Vec<PathBuf>,
}

impl Collected {
    /// Ids of the points without a run.
    pub fn missing(&self) -> Vec<&str> {
        self.rows
            .iter()
            .filter(|r| r.status == Status::Missing)
            .map(|r| r.id.as_str())
            .collect()
    }
}

/// Assembles `DIR/sweep.csv` and the figures from the point directories (after the
/// shards of a sweep have run).
pub fn collect(dir: &Path) -> Result<Collected, SweepError> {
    let record = Record::load(dir)?;
    let axes = record.axes();
    let rows: Vec<Row> = record
        .points
        .iter()
        .map(|p| read_row(&p.id, &p.values, &dir.join("points").join(&p.id)))
        .collect();
    let csv = dir.join("sweep.csv");
    write_atomic(&csv, &table::render(&axes, &rows))?;
    let mut written = vec![csv];
    written.extend(plots::draw(dir, &record, &rows, None)?);
    written.extend(compare::write(dir, &record, &rows)?);
    Ok(Collected { rows, written })
}

/// Redraws the figures of `DIR` from `DIR/sweep.csv` (and the design in `sweep.json`);
/// `quantity` is the column of the heat map or line plot (default: penetration depth).
pub fn plot(dir: &Path, quantity: Option<&str>) -> Result<Vec<PathBuf>, SweepError> {
    let record = Record::load(dir)?;
    let path = dir.join("sweep.csv");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| SweepError::Input(format!("{}: {e}", path.display())))?;
    let (axes, rows) =
        table::parse(&text).map_err(|m| SweepError::Input(format!("{}: {m}", path.display())))?;
    if axes != record.axes() {
        return Err(SweepError::Input(format!(
            "{}: axis columns {axes:?} differ from sweep.json's {:?}",
            path.display(),
            record.axes()
        )));
    }
    if let Some(q) = quantity {
        if !table::quantities().contains(&q) {
            return Err(SweepError::Input(format!(
                "--quantity {q}: not a column of sweep.csv; one of {}",
                table::quantities().join(", ")
            )));
        }
    }
    Ok(plots::draw(dir, &record, &rows, quantity)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expressions_evaluate_with_paths() {
        let look = |p: &str| match p {
            "substrate.width" => Some(6.0),
            "substrate.spacing" => Some(10.0),
            _ => None,
        };
        assert_eq!(
            eval("(substrate.width + substrate.spacing) / 2", &look),
            Ok(8.0)
        );
        assert_eq!(eval("-2 * 3 + 1e1 - 4/2", &look), Ok(2.0));
        assert!(
            eval("substrate.nope + 1", &look)
                .unwrap_err()
                .contains("substrate.nope")
        );
        assert!(eval("(1 + 2", &look).is_err());
        assert!(eval("1 / 0", &look).is_err());
        assert!(eval("1 2", &look).is_err());
    }

    #[test]
    fn struct_valued_axes_are_one_line_in_the_table() {
        // An axis over a whole section (the PAC's semi-axes reading in one value): the
        // base's value comes from the resolved case, written over several lines.
        let dir = std::env::temp_dir().join(format!("cellsim-sweep-struct-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/fast/push-pull-short.ron");
        let file = dir.join("pac.ron");
        std::fs::write(
            &file,
            format!(
                "(name: \"pac\", base: {:?}, design: OneAtATime([(path: \"active.pac\", \
                 values: [(inner_semi_axes: (10.0, 9.0),\n outer_semi_axes: (15.0, 14.0), \
                 clip_to_cell: true)])]))",
                base.display().to_string()
            ),
        )
        .unwrap();
        let plan = Plan::load(&file).unwrap();
        assert_eq!(plan.points.len(), 2);
        for p in &plan.points {
            assert!(!p.values[0].contains('\n'), "{:?}", p.values[0]);
            assert!(p.case.is_ok(), "{:?}", p.case);
        }
        assert!(plan.points[0].values[0].contains("clip_to_cell: false"));
        assert!(plan.points[1].values[0].contains("clip_to_cell: true"));
        // The table with those values reads back.
        let axes = vec!["active.pac".to_string()];
        let rows: Vec<Row> = plan
            .points
            .iter()
            .map(|p| Row::bare(&p.id, p.values.clone(), Status::Missing, "not run"))
            .collect();
        let (a, r) = table::parse(&table::render(&axes, &rows)).unwrap();
        assert_eq!((a, r), (axes, rows));
        std::fs::remove_dir_all(&dir).ok();
    }

    fn repo(path: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
    }

    /// `PATH=VALUE` of the point's overrides, in order.
    fn overrides_of(p: &Point) -> Vec<String> {
        p.overrides.iter().map(Override::to_string).collect()
    }

    #[test]
    fn variant_axes_apply_their_sets_in_axis_order() {
        let dir =
            std::env::temp_dir().join(format!("cellsim-sweep-variants-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("v.ron");
        std::fs::write(
            &file,
            format!(
                r#"(name: "v", base: {:?}, set: ["solver.rtol=1e-3"], design: Grid([
                    (name: "reading", variants: [(name: "none"), (name: "clip", set: ["active.pac.clip_to_cell=true", "active.pac.inner_semi_axes=(10.0, 9.0)", "active.pac.outer_semi_axes=(15.0, 14.0)"])]),
                    (name: "scene", variants: [(name: "pp"), (name: "pull", set: ["active.pac=None"])]),
                ]))"#,
                repo("cases/fast/push-pull-short.ron").display().to_string()
            ),
        )
        .unwrap();
        let plan = Plan::load(&file).unwrap();
        let ids: Vec<&str> = plan.points.iter().map(|p| p.id.as_str()).collect();
        assert_eq!(ids, ["g0_0", "g0_1", "g1_0", "g1_1"]);
        assert_eq!(plan.points[3].values, ["clip", "pull"]);
        assert_eq!(
            overrides_of(&plan.points[3]),
            [
                "solver.rtol=1e-3",
                "active.pac.clip_to_cell=true",
                "active.pac.inner_semi_axes=(10.0, 9.0)",
                "active.pac.outer_semi_axes=(15.0, 14.0)",
                "active.pac=None"
            ]
        );
        let case = |k: usize| plan.points[k].case.as_ref().unwrap().0.clone();
        // The later axis wins: the pull scene has no PAC whatever the reading.
        assert!(case(3).active.pac.is_none() && case(1).active.pac.is_none());
        assert!(case(2).active.pac.as_ref().unwrap().clip_to_cell);
        assert!(!case(0).active.pac.as_ref().unwrap().clip_to_cell);
        assert_eq!(case(0).solver.rtol, 1e-3);
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The scene a `cases/` file describes, its name and description as the sweep's.
    fn as_scene(file: &str, like: &Case) -> Case {
        let mut c = Case::load(repo(file)).unwrap();
        c.name = like.name.clone();
        c.description = like.description.clone();
        c
    }

    #[test]
    fn paper_fidelity_scenes_are_the_scene_files() {
        let plan = Plan::load(&repo("cases/sweeps/paper-fidelity.ron")).unwrap();
        assert_eq!(plan.points.len(), 72);
        assert!(plan.points.iter().all(|p| p.case.is_ok()));
        let point = |reading: &str, scene: &str| -> Case {
            let p = plan
                .points
                .iter()
                .find(|p| p.values == [reading, scene])
                .unwrap_or_else(|| panic!("no point ({reading}, {scene})"));
            p.case.as_ref().unwrap().0.clone()
        };
        let base = "baseline (MODEL.md)";
        for (scene, file) in [
            ("flat", "cases/flat.ron"),
            ("push", "cases/pillars-push.ron"),
            ("pull", "cases/pillars-pull.ron"),
            ("push-pull", "cases/pillars-push-pull.ron"),
            ("upside-down", "cases/upside-down.ron"),
        ] {
            let c = point(base, scene);
            assert_eq!(c, as_scene(file, &c), "{scene}");
            assert_eq!(c.name, file[6..file.len() - 4], "{scene}");
        }
        // The control: push-pull continued to the upside-down scene's end, gravity kept.
        let c = point(base, "control");
        let mut pp = as_scene("cases/pillars-push-pull.ron", &c);
        pp.phases.t_end = 60_000.0;
        assert_eq!(c, pp);
        // A reading changes what it says on every scene, and the scenes keep theirs.
        let pac = point("PAC semi-axes, clipped", "push").active.pac.unwrap();
        assert!(pac.clip_to_cell && pac.inner_semi_axes == (10.0, 9.0));
        assert_eq!(point("PAC semi-axes, clipped", "pull"), point(base, "pull"));
        assert_eq!(point("PAC semi-axes, clipped", "flat"), point(base, "flat"));
        for scene in [
            "flat",
            "push",
            "pull",
            "push-pull",
            "upside-down",
            "control",
        ] {
            let a = point("best supported", scene).adhesion.unwrap();
            assert!(a.jacobian_factor && a.layer_excludes_substrate, "{scene}");
            assert_eq!(point("e_f = 0.8 µm", scene).adhesion.unwrap().e_f, 0.8);
        }
        // The flip reading changes the upside-down scene only.
        let flip = "gravity flipped in 100 s";
        assert_eq!(point(flip, "upside-down").gravity.flip_duration, 100.0);
        for scene in ["flat", "push", "pull", "push-pull", "control"] {
            assert_eq!(point(flip, scene), point(base, scene), "{scene}");
        }
        assert!(point("best supported", "pull").active.pac.is_none());
        assert!(point("best supported", "flat").active.bottom.is_none());
    }

    #[test]
    fn paper_fidelity_references_are_the_papers() {
        use crate::output::paper::REPORTED;
        let plan = Plan::load(&repo("cases/sweeps/paper-fidelity.ron")).unwrap();
        let table = plan.table.unwrap();
        let scene = |s: &str| match s {
            "flat" => "flat",
            "pillars-push" => "push",
            "pillars-pull" => "pull",
            "pillars-push-pull" => "push-pull",
            "upside-down" => "upside-down",
            _ => "?",
        };
        // Every value the paper reports is a column's reference on its scene (strains
        // in %), and every reference is one the paper reports there.
        let refs: Vec<(&str, f64)> = table
            .columns()
            .filter_map(|c| Some((c.of.as_str(), c.reference?)))
            .collect();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
        for r in REPORTED.iter() {
            let pillar_start = r.scene != "pillars-push"
                && matches!(
                    r.quantity,
                    crate::output::paper::Quantity::NucleusDisplacement(
                        crate::output::paper::When::GravityEnd
                            | crate::output::paper::When::SpreadingEnd
                    )
                );
            if pillar_start {
                continue; // the same case as push until T_as0: the push columns
            }
            let found = refs.iter().any(|&(of, v)| {
                of == scene(r.scene) && (close(v, r.value) || close(v, 100.0 * r.value))
            });
            assert!(
                found,
                "{} {:?} {} has no column",
                r.scene, r.quantity, r.value
            );
        }
        for (of, v) in refs {
            assert!(
                REPORTED
                    .iter()
                    .any(|r| scene(r.scene) == of
                        && (close(v, r.value) || close(v, 100.0 * r.value))),
                "{of}: reference {v} is not the paper's"
            );
        }
    }

    #[test]
    fn shards_split_the_points_round_robin() {
        assert_eq!(parse_shard("1/4"), Ok((1, 4)));
        assert!(
            parse_shard("4/4").is_err() && parse_shard("x").is_err() && parse_shard("0/0").is_err()
        );
        let mine: Vec<usize> = (0..10).filter(|&k| in_shard(k, Some((1, 3)))).collect();
        assert_eq!(mine, [1, 4, 7]);
    }
}
