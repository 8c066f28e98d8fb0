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
//! `DIR/points/<id>/` holds `case.ron` (the resolved case, as `cellsim check` prints it),
//! `resolved.txt` (the same case with every field, those at their defaults included, as the
//! code that ran it read them) and the run's usual files, or `invalid.txt` (the validation
//! message), or `error.txt` (a run that could not start). `DIR/sweep.json` records the
//! design and the settings, `DIR/sweep.csv` the results ([`table`]). Running the same sweep
//! again skips the points whose `case.ron` and `resolved.txt` are unchanged (a default
//! changed since the point ran leaves `case.ron` as it was, not `resolved.txt`) and whose
//! summary says finished (or failed, unless `retry_failed`); `--shard i/K` runs the points
//! k with k mod K = i only, and [`collect`] assembles the table and figures from the point
//! directories.

pub mod compare;
pub mod design;
pub mod plots;
pub mod slurm;
pub mod table;

use std::collections::{HashMap, VecDeque};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};

use crate::case::overrides::{self, parse_number, value_at};
use crate::case::{Case, CaseError, Override, Substrate};
use crate::render::OutputError;
use crate::run::{self, Progress, RunError, RunOptions};
use crate::run_files::FailureKind;
use crate::solver::Limits;
use crate::stop::StopFlag;

pub use compare::TableSpec;
use design::DesignPoint;
pub use design::{Design, DesignSpec, Kind};
pub use table::{Row, Status, Stopped};

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
    #[serde(default, deserialize_with = "present")]
    pub table: Option<TableSpec>,
}

/// A field of a sweep file written without `Some(...)`: present means `Some` (the
/// design's axes, the table and its columns).
fn present<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
) -> Result<Option<T>, D::Error> {
    T::deserialize(d).map(Some)
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
    /// Wall-clock budget of each run \[s\].
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

/// Reads and parses the sweep file; a parse error is located by line and column.
fn read_sweep_file(sweep_file: &Path) -> Result<SweepFile, SweepError> {
    let text = std::fs::read_to_string(sweep_file).map_err(|e| {
        SweepError::Input(format!(
            "{}: cannot read the sweep file: {e}",
            sweep_file.display()
        ))
    })?;
    ron::Options::default()
        .from_str(text.trim_start_matches('\u{FEFF}'))
        .map_err(|e| SweepError::Input(located(sweep_file, &e)))
}

/// Checks that the sweep's name is a single path component: it names a directory.
fn check_name(name: &str) -> Result<(), String> {
    let name_ok = !name.is_empty()
        && !name.contains(['/', '\\'])
        && name != "."
        && name != ".."
        && !name.chars().any(char::is_control);
    if name_ok {
        Ok(())
    } else {
        Err(format!(
            "name = {name:?} is not allowed (a single path component, not empty)"
        ))
    }
}

/// Reads the base case file `path` (`base = name` in the sweep file) as text.
fn read_base(path: &Path, name: &str) -> Result<String, String> {
    let bytes = std::fs::read(path)
        .map_err(|e| format!("base = {name:?}: cannot read {}: {e}", path.display()))?;
    String::from_utf8(bytes)
        .map_err(|_| format!("base = {name:?}: {} is not UTF-8 text", path.display()))
}

/// Parses the sweep's `set`, each override named by its source.
fn parse_set(set: &[String]) -> Result<Vec<Override>, String> {
    set.iter()
        .map(|s| {
            Override::parse(s)
                .map(|o| o.from_source(format!("sweep set `{s}`")))
                .map_err(|m| format!("set: {m}"))
        })
        .collect()
}

/// The base case as the points are resolved against it.
struct Base {
    /// The base case file's text.
    text: String,
    /// Its path, as errors name it.
    label: String,
    /// The base with `set`, resolved (RON), if valid: the values of the axes a point
    /// leaves alone.
    resolved: Option<String>,
    /// A case with every default (RON): the values derived expressions may read that the
    /// base does not write.
    defaults: String,
}

impl Base {
    /// The base of text `text` read from `path`, with the sweep's `set`.
    fn new(text: String, path: &Path, set: &[Override]) -> Base {
        let label = path.display().to_string();
        let resolved = Case::from_str_with_overrides(&text, &label, set)
            .ok()
            .and_then(|c| c.to_ron().ok());
        let defaults = Case::new("defaults", Substrate::pillars(), 1.0)
            .to_ron()
            .unwrap_or_default();
        Base {
            text,
            label,
            resolved,
            defaults,
        }
    }
}

/// Resolves a parsed sweep file: its base, overrides, design, table and points. Errors are
/// what follows the sweep file's name in the message.
fn resolve_plan(sweep_file: &Path, spec: SweepFile) -> Result<Plan, String> {
    check_name(&spec.name)?;
    let dir = sweep_file.parent().unwrap_or(Path::new("."));
    let base_path = dir.join(&spec.base);
    let base_text = read_base(&base_path, &spec.base)?;
    let set = parse_set(&spec.set)?;
    let design = Design::from_spec(&spec.design).map_err(|m| format!("design: {m}"))?;
    for d in &spec.derive {
        Override::new(&d.path, "0").map_err(|m| format!("derive: {m}"))?;
    }
    let table = spec
        .table
        .clone()
        .map(|t| t.resolve(&design, &spec.name, dir))
        .transpose()
        .map_err(|e| e.to_string())?;
    let base = Base::new(base_text, &base_path, &set);
    let mut points = design
        .points()
        .into_iter()
        .map(|dp| resolve_point(&base, &design, &set, &spec.derive, dp))
        .collect::<Result<Vec<_>, _>>()?;
    if design.kind == Kind::OneAtATime {
        drop_base_repeats(&mut points);
    }
    Ok(Plan {
        name: spec.name,
        sweep_file: sweep_file.to_path_buf(),
        base: base_path,
        design,
        set,
        derive: spec.derive,
        table,
        points,
    })
}

/// Resolves one point of the design: `set`, its axis values and the derived fields
/// applied to the base, its case and its value on each axis.
fn resolve_point(
    base: &Base,
    design: &Design,
    set: &[Override],
    derive: &[Derived],
    dp: DesignPoint,
) -> Result<Point, String> {
    let mut ovs = set.to_vec();
    ovs.extend(axis_overrides(design, &dp.values)?);
    for d in derive {
        let o = derived_override(base, &ovs, d, &dp.id)?;
        ovs.push(o);
    }
    let case = resolve_case(base, &ovs, &dp.id)?;
    let values = point_values(design, &dp.values, base.resolved.as_deref());
    Ok(Point {
        id: dp.id,
        values,
        overrides: ovs,
        case,
    })
}

/// The overrides of a point's axis values, in axis order: a variant's set, or
/// `PATH=VALUE` (an axis the point leaves alone gives none).
fn axis_overrides(design: &Design, values: &[Option<String>]) -> Result<Vec<Override>, String> {
    let mut ovs = Vec::new();
    for (axis, v) in design.axes.iter().zip(values) {
        let Some(v) = v else { continue };
        if let Some(set) = axis.variant_set(v) {
            for o in set {
                let origin = format!("sweep axis `{}`, variant `{v}`: `{o}`", axis.path);
                ovs.push(
                    Override::parse(o)
                        .map(|o| o.from_source(origin))
                        .map_err(|m| format!("design: axis `{}`: variant `{v}`: {m}", axis.path))?,
                );
            }
        } else {
            let o = Override::new(&axis.path, v)
                .map_err(|m| format!("design: axis `{}`: value {m}", axis.path))?;
            ovs.push(o.from_source(format!("sweep axis `{}` = {v}", axis.path)));
        }
    }
    Ok(ovs)
}

/// The override of derived field `d` at point `id`: its expression evaluated on the
/// point's case as `ovs` make it (a field neither sets nor the base writes: its default).
fn derived_override(
    base: &Base,
    ovs: &[Override],
    d: &Derived,
    id: &str,
) -> Result<Override, String> {
    let written = overrides::apply(&base.text, ovs).ok().map(|e| e.text);
    let lookup = |path: &str| -> Option<f64> {
        if let Some(o) = ovs.iter().rev().find(|o| o.path == path) {
            return parse_number(&o.value);
        }
        written
            .as_deref()
            .and_then(|t| value_at(t, path))
            .or_else(|| value_at(&base.defaults, path))
            .and_then(|v| parse_number(&v))
    };
    let v = eval(&d.expr, &lookup)
        .map_err(|m| format!("derive `{}` = `{}` at point {id}: {m}", d.path, d.expr))?;
    let value = design::fmt_number(v);
    let origin = format!("sweep derive `{}` = `{}` = {value}", d.path, d.expr);
    Ok(Override::new(&d.path, &value)
        .map_err(|m| format!("derive: {m}"))?
        .from_source(origin))
}

/// The case of point `id` and its text, or `Ok(Err(message))` when it breaks a rule of the
/// schema (an invalid point); `Err` when an override does not apply at all.
fn resolve_case(
    base: &Base,
    ovs: &[Override],
    id: &str,
) -> Result<Result<(Case, String), String>, String> {
    match Case::from_str_with_overrides(&base.text, &base.label, ovs) {
        Ok(c) => {
            let text = c.to_ron().map_err(|e| format!("point {id}: {e}"))?;
            Ok(Ok((c, text)))
        }
        Err(e @ CaseError::Invalid { .. }) => Ok(Err(e.to_string())),
        Err(e) => Err(format!("point {id}: {e}")),
    }
}

/// A point's value on each axis: its own, the base's for an axis it leaves alone, or
/// `(base)` for a variant axis it leaves alone.
fn point_values(design: &Design, values: &[Option<String>], base: Option<&str>) -> Vec<String> {
    // On one line: a struct value (a whole `active.pac`) is written over several lines in
    // a case, and sweep.csv holds one point per line.
    design
        .axes
        .iter()
        .zip(values)
        .map(|(a, v)| match v {
            Some(v) => single_line(v),
            // A variant axis left alone: the base as it is.
            None if a.is_variants() => "(base)".to_string(),
            None => base
                .and_then(|t| value_at(t, &a.path))
                .map(|v| single_line(&v))
                .unwrap_or_default(),
        })
        .collect()
}

/// One at a time: drops the points after the first (the base) whose case is the base's,
/// as a value equal to the base's gives the base point again.
fn drop_base_repeats(points: &mut Vec<Point>) {
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

impl Plan {
    /// Reads the sweep file and its base case and resolves every point. Errors name the
    /// file (and line and column where ron tells them) or the axis.
    pub fn load(sweep_file: &Path) -> Result<Plan, SweepError> {
        Self::load_with(sweep_file, &[])
    }

    /// [`Plan::load`] with `set` (`PATH=VALUE`, the command line's `--set`) applied to
    /// every point after the sweep file's own `set`, before the design's values: the same
    /// map on another mesh or tolerance without another sweep file.
    pub fn load_with(sweep_file: &Path, set: &[String]) -> Result<Plan, SweepError> {
        let mut spec = read_sweep_file(sweep_file)?;
        spec.set.extend(set.iter().cloned());
        resolve_plan(sweep_file, spec).map_err(|m| {
            let from = if set.is_empty() {
                ""
            } else {
                " (with the command line's --set)"
            };
            SweepError::Input(format!("{}{from}: {m}", sweep_file.display()))
        })
    }

    /// Each point on one line, as `--list` prints them: id, value on each axis, and valid
    /// or the validation message.
    pub fn listing(&self) -> Vec<String> {
        let axes: Vec<&str> = self.design.axes.iter().map(|x| x.path.as_str()).collect();
        self.points
            .iter()
            .map(|p| {
                let at = assignments(&axes, &p.values).join(" ");
                match &p.case {
                    Ok(_) => format!("{} {at}: valid", p.id),
                    Err(m) => format!("{} {at}: invalid: {}", p.id, m.replace('\n', "; ")),
                }
            })
            .collect()
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
    let summary = crate::run_files::read::read_summary(dir);
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
    let stopped = match &s.failure {
        Some(f) if !s.finished => Stopped {
            class: f.kind.name(),
            t: f.t_stop,
            element: f.place.as_ref().map(|p| p.element),
            x: std::array::from_fn(|k| f.place.as_ref().and_then(|p| p.x.get(k).copied())),
        },
        _ => Stopped::of_status(status),
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
        stopped,
        extras: [
            s.final_values_3d.map(|o| o.contact_area),
            s.final_values_3d.map(|o| o.contact_area_ref),
            s.strain_nucleus_max,
        ],
        events: (!s.events.is_empty()).then(|| {
            let start = |phase: &str| s.events.iter().find(|e| e.phase == phase).and_then(|e| e.t);
            [start("adhesion"), start("active")]
        }),
        reason: table::one_line(&reason),
    }
}

/// The file of a point's directory that holds [`resolved`].
const RESOLVED: &str = "resolved.txt";

/// A case with every field, those at their defaults included (which `case.ron` omits):
/// what a point's run is compared by, beside its text.
fn resolved(case: &Case) -> String {
    format!("{case:#?}\n")
}

/// Whether a point's directory holds a run of `case` (`text`: its `case.ron`) that need not
/// run again. A directory from before `resolved.txt` was written runs again.
fn is_done(dir: &Path, case: &Case, text: &str, retry_failed: bool) -> bool {
    let holds = |name: &str, want: &str| {
        std::fs::read_to_string(dir.join(name)).ok().as_deref() == Some(want)
    };
    if !holds("case.ron", text) || !holds(RESOLVED, &resolved(case)) {
        return false;
    }
    match crate::run_files::read::read_summary(dir) {
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
    /// Wall-clock budget of each run \[s\].
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
    /// Wall time of the whole command \[s\].
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

    /// One line: the counts, what this command did, its wall time and where the outputs
    /// of sweep `name` are (`out`).
    pub fn summary(&self, name: &str, out: &Path) -> String {
        format!(
            "{}: {} ({} run, {} reused{}) in {:.1} s wall; outputs in {}",
            name,
            self.counts(),
            self.ran,
            self.reused,
            if self.copied > 0 {
                format!(", {} copied", self.copied)
            } else {
                String::new()
            },
            self.wall_seconds,
            out.display()
        )
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

/// A `--shard` value that is not `i/K` with 0 ≤ i < K.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("--shard `{0}` is not i/K with 0 <= i < K (e.g. 0/4)")]
pub struct ShardError(pub String);

/// Parses `i/K` (0 ≤ i < K).
pub fn parse_shard(s: &str) -> Result<(usize, usize), ShardError> {
    let err = || ShardError(s.to_string());
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

/// The rows and counts the threads running a sweep's points share.
struct Shared {
    /// sweep.csv as it is appended to, and whether it has the phase starts' columns.
    csv: Option<(std::fs::File, bool)>,
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
    let record = write_record(plan, opts)?;
    let axes = record.axes();

    let mine: Vec<usize> = (0..plan.points.len())
        .filter(|&k| in_shard(k, opts.shard))
        .collect();
    let mut todo = Todo::sort(plan, &mine, &points_dir, opts.retry_failed)?;
    todo.copy_done(plan, &points_dir)?;
    let to_run = todo.queue.len();
    let total = to_run + todo.to_copy();

    // sweep.csv as points finish (not when sharded: shards share the directory).
    let csv_path = out.join("sweep.csv");
    let csv = match opts.shard {
        None => {
            // The phase starts' columns when some point's cell starts its phases itself.
            let events = plan.points.iter().any(|p| {
                p.case.as_ref().is_ok_and(|(c, _)| {
                    c.phases.adhesion_start.is_some() || c.phases.active_start.is_some()
                })
            });
            Some((start_csv(&csv_path, &axes, &todo.rows, events)?, events))
        }
        Some(_) => None,
    };
    let log = Log::new(plan, opts, total);
    if opts.progress {
        log.say(start_message(plan, opts, mine.len(), &todo));
    }
    let Todo {
        rows,
        queue,
        copies,
        reused,
        copied,
    } = todo;
    let runner = Runner {
        plan,
        opts,
        points_dir: &points_dir,
        axes: &axes,
        copies: &copies,
        log: &log,
        queue: Mutex::new(queue),
        shared: Mutex::new(Shared {
            csv,
            rows,
            done: 0,
            failed: 0,
            copied,
        }),
        first_error: Mutex::new(None),
    };
    let jobs = opts.jobs.clamp(1, to_run.max(1));
    crate::solver::share_cores_among(jobs);
    let (rows, copied) = runner.run(jobs)?;
    let rows = rows_in_order(plan, &mine, &points_dir, &rows);
    let written = match opts.shard {
        None => write_table_and_figures(out, &record, &rows)?,
        Some(_) => Vec::new(),
    };
    Ok(SweepReport {
        rows,
        ran: to_run,
        reused,
        copied,
        written,
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

/// Writes `DIR/sweep.json`, the plan with the command's settings; returns the record.
fn write_record(plan: &Plan, opts: &SweepOptions) -> Result<Record, SweepError> {
    let record = plan.record(Settings {
        jobs: opts.jobs,
        retry_failed: opts.retry_failed,
        max_wall: opts.max_wall,
        shards: opts.shard.map(|(_, k)| k),
    });
    let path = opts.out.join("sweep.json");
    let json = serde_json::to_string_pretty(&record).map_err(|e| SweepError::Io {
        path: path.display().to_string(),
        source: std::io::Error::other(e),
    })?;
    write_atomic(&path, &json)?;
    Ok(record)
}

/// The points of a sweep command sorted by what they need.
struct Todo {
    /// By point number, the rows of the points settled before anything runs.
    rows: Vec<Option<Row>>,
    /// The points to run, in design order.
    queue: VecDeque<usize>,
    /// By point j, the later points whose case is j's: they get a copy of j's directory.
    copies: HashMap<usize, Vec<usize>>,
    /// Points whose run was already there.
    reused: usize,
    /// Copies made of points already done.
    copied: usize,
}

impl Todo {
    /// Sorts the points `mine`: an invalid point gets its message (unless it has it), a
    /// point whose run is there is reused, a point whose case is an earlier one's waits
    /// for a copy of it, the others are queued.
    fn sort(
        plan: &Plan,
        mine: &[usize],
        points_dir: &Path,
        retry_failed: bool,
    ) -> Result<Todo, SweepError> {
        let mut todo = Todo {
            rows: vec![None; plan.points.len()],
            queue: VecDeque::new(),
            copies: HashMap::new(),
            reused: 0,
            copied: 0,
        };
        // A point whose resolved case is an earlier point's is not run again: it gets a
        // copy of that point's directory (runs are deterministic), e.g. a reading that
        // leaves one of the scenes of a variant axis unchanged.
        let mut first_with: HashMap<&str, usize> = HashMap::new();
        for &k in mine {
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
                    todo.rows[k] = Some(read_row(&p.id, &p.values, &dir));
                }
                Ok((case, text)) if is_done(&dir, case, text, retry_failed) => {
                    todo.reused += 1;
                    todo.rows[k] = Some(read_row(&p.id, &p.values, &dir));
                    first_with.entry(text).or_insert(k);
                }
                Ok((_, text)) => match first_with.get(text.as_str()) {
                    Some(&j) => todo.copies.entry(j).or_default().push(k),
                    None => {
                        first_with.insert(text, k);
                        todo.queue.push_back(k);
                    }
                },
            }
        }
        Ok(todo)
    }

    /// Makes the copies of the points already done now.
    fn copy_done(&mut self, plan: &Plan, points_dir: &Path) -> Result<(), SweepError> {
        for (j, ks) in self.copies.iter_mut() {
            if self.rows[*j].is_some() {
                for &k in ks.iter() {
                    let p = &plan.points[k];
                    let dir = points_dir.join(&p.id);
                    copy_point(&points_dir.join(&plan.points[*j].id), &dir)?;
                    self.rows[k] = Some(read_row(&p.id, &p.values, &dir));
                    self.copied += 1;
                }
                ks.clear();
            }
        }
        Ok(())
    }

    /// Copies still to make, once the points they copy have run.
    fn to_copy(&self) -> usize {
        self.copies.values().map(Vec::len).sum()
    }
}

/// Creates `sweep.csv` with its header and the rows settled so far (the others are
/// appended as they finish).
fn start_csv(
    path: &Path,
    axes: &[String],
    rows: &[Option<Row>],
    events: bool,
) -> Result<std::fs::File, SweepError> {
    let mut f = std::fs::File::create(path).map_err(SweepError::io(path))?;
    let mut text = table::header(axes, events) + "\n";
    for r in rows.iter().flatten() {
        text += &(table::line(r, events) + "\n");
    }
    f.write_all(text.as_bytes()).map_err(SweepError::io(path))?;
    Ok(f)
}

/// The first line of a sweep's progress: its points and what they need.
fn start_message(plan: &Plan, opts: &SweepOptions, mine: usize, todo: &Todo) -> String {
    let (to_run, to_copy) = (todo.queue.len(), todo.to_copy());
    let total = to_run + to_copy;
    format!(
        "{}: {} points{}: {} to run, {} reused, {} invalid{}; {} at once",
        plan.name,
        mine,
        opts.shard
            .map(|(i, k)| format!(" in shard {i}/{k}"))
            .unwrap_or_default(),
        to_run,
        todo.reused,
        mine - total - todo.reused - todo.copied,
        if to_copy + todo.copied > 0 {
            format!(
                ", {} the same case as another point (copied)",
                to_copy + todo.copied
            )
        } else {
            String::new()
        },
        opts.jobs.min(to_run.max(1))
    )
}

/// Where a sweep's progress goes: a bar on a terminal, a line per point otherwise, or
/// nowhere.
struct Log {
    bar: ProgressBar,
    /// Whether the bar shows (progress asked for, stderr a terminal).
    visible: bool,
    /// Whether progress was asked for.
    progress: bool,
    /// Points to run or copy.
    total: usize,
}

impl Log {
    /// The log of `total` points of `plan`.
    fn new(plan: &Plan, opts: &SweepOptions, total: usize) -> Log {
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
        Log {
            bar,
            visible,
            progress: opts.progress,
            total,
        }
    }

    /// Prints `msg` above the bar, or on stderr without one.
    fn say(&self, msg: String) {
        if self.visible {
            self.bar.println(msg);
        } else {
            let _ = writeln!(std::io::stderr(), "{msg}");
        }
    }

    /// Advances the bar past a finished point (printing its `line` unless it finished
    /// well), or prints the line without a bar.
    fn point(&self, row: &Row, line: String, failed: usize) {
        if self.visible {
            self.bar.inc(1);
            self.bar.set_message(format!("({failed} failed)"));
            if row.status != Status::Finished {
                self.bar.println(line);
            }
        } else if self.progress {
            let _ = writeln!(std::io::stderr(), "{line}");
        }
    }
}

/// A finished point: its number, its row, and the id of the point it is a copy of.
type Done<'a> = (usize, Row, Option<&'a str>);

/// What the threads running a sweep's points share.
struct Runner<'a> {
    plan: &'a Plan,
    opts: &'a SweepOptions,
    points_dir: &'a Path,
    axes: &'a [String],
    copies: &'a HashMap<usize, Vec<usize>>,
    log: &'a Log,
    queue: Mutex<VecDeque<usize>>,
    shared: Mutex<Shared>,
    first_error: Mutex<Option<SweepError>>,
}

impl<'a> Runner<'a> {
    /// Runs the queue on `jobs` threads; returns the rows by point number and the count of
    /// copies made, or the first error writing a point's directory.
    fn run(self, jobs: usize) -> Result<(Vec<Option<Row>>, usize), SweepError> {
        std::thread::scope(|scope| {
            for _ in 0..jobs {
                scope.spawn(|| self.work());
            }
        });
        self.log.bar.finish_and_clear();
        if let Some(e) = self.first_error.into_inner().ok().flatten() {
            return Err(e);
        }
        Ok(self
            .shared
            .into_inner()
            .map(|s| (s.rows, s.copied))
            .unwrap_or_default())
    }

    /// One thread: runs points off the queue until it is empty, the sweep is interrupted
    /// or a point's directory cannot be written.
    fn work(&self) {
        loop {
            if self.opts.interrupt.is_set() {
                break;
            }
            let next = self.queue.lock().ok().and_then(|mut q| q.pop_front());
            let Some(k) = next else { break };
            let p = &self.plan.points[k];
            let dir = self.points_dir.join(&p.id);
            let t0 = Instant::now();
            let row = match run_point(p, &dir, self.opts) {
                Ok(row) => row,
                Err(e) => {
                    self.fail(e);
                    break;
                }
            };
            let wall = t0.elapsed().as_secs_f64();
            let done = self.with_copies(k, &dir, row);
            if !self.record(done, wall) {
                break;
            }
        }
    }

    /// Point `k`'s row, then its copies' (made now, unless it was interrupted: then they
    /// run later).
    fn with_copies(&self, k: usize, dir: &Path, row: Row) -> Vec<Done<'a>> {
        let p = &self.plan.points[k];
        let mut done = vec![(k, row, None)];
        if done[0].1.status != Status::Interrupted {
            for &c in self.copies.get(&k).into_iter().flatten() {
                let q = &self.plan.points[c];
                let cdir = self.points_dir.join(&q.id);
                match copy_point(dir, &cdir) {
                    Ok(()) => {
                        done.push((c, read_row(&q.id, &q.values, &cdir), Some(p.id.as_str())))
                    }
                    Err(e) => self.fail(e),
                }
            }
        }
        done
    }

    /// Counts finished points, appends their lines to sweep.csv and logs them (`wall`: the
    /// run's wall time); false if another thread panicked holding the rows.
    fn record(&self, done: Vec<Done<'a>>, wall: f64) -> bool {
        let Ok(mut sh) = self.shared.lock() else {
            return false;
        };
        for (k, row, copy_of) in done {
            sh.done += 1;
            sh.copied += usize::from(copy_of.is_some());
            if row.status == Status::Failed {
                sh.failed += 1;
            }
            if let Some((f, events)) = sh.csv.as_mut() {
                let _ = f
                    .write_all((table::line(&row, *events) + "\n").as_bytes())
                    .and_then(|_| f.flush());
            }
            let total = self.log.total;
            let line = match copy_of {
                None => point_line(&row, self.axes, sh.done, total, wall),
                Some(of) => copy_line(&row, self.axes, sh.done, total, of),
            };
            self.log.point(&row, line, sh.failed);
            sh.rows[k] = Some(row);
        }
        true
    }

    /// Keeps `e` if it is the first error.
    fn fail(&self, e: SweepError) {
        if let Ok(mut f) = self.first_error.lock() {
            f.get_or_insert(e);
        }
    }
}

/// The rows of the points `mine`, in design order: a point without one in `rows` (not
/// run, the sweep interrupted) is read from its directory.
fn rows_in_order(plan: &Plan, mine: &[usize], points_dir: &Path, rows: &[Option<Row>]) -> Vec<Row> {
    mine.iter()
        .map(|&k| {
            let p = &plan.points[k];
            rows[k]
                .clone()
                .unwrap_or_else(|| read_row(&p.id, &p.values, &points_dir.join(&p.id)))
        })
        .collect()
}

/// Writes `DIR/sweep.csv` from `rows` and draws the figures and comparison table; returns
/// the files written.
fn write_table_and_figures(
    dir: &Path,
    record: &Record,
    rows: &[Row],
) -> Result<Vec<PathBuf>, SweepError> {
    let csv = dir.join("sweep.csv");
    write_atomic(&csv, &table::render(&record.axes(), rows))?;
    let mut written = vec![csv];
    written.extend(plots::draw(dir, record, rows, None)?);
    written.extend(compare::write(dir, record, rows)?);
    Ok(written)
}

/// `PATH=VALUE` of a point on each axis.
fn assignments(axes: &[impl AsRef<str>], values: &[String]) -> Vec<String> {
    axes.iter()
        .zip(values)
        .map(|(a, v)| format!("{}={v}", a.as_ref()))
        .collect()
}

/// The log line of a finished point.
fn point_line(row: &Row, axes: &[String], n: usize, total: usize, wall: f64) -> String {
    let at = assignments(axes, &row.values);
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
    let at = assignments(axes, &row.values);
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
    write_atomic(&dir.join(RESOLVED), &resolved(case))?;
    let ropts = RunOptions {
        out: dir.to_path_buf(),
        // Points run `jobs` at a time, each on its own thread: their element loops stay on
        // it rather than share rayon's pool with the other points (two coarse 3-D points
        // at --jobs 2 on 2 cores: 394 s with the pool, 365 s without, one pair); the
        // results are the same bits either way.
        settings: crate::solver::Settings {
            parallel_elements: case.solver.parallel_elements && opts.jobs <= 1,
            ..case.solver.clone()
        },
        limits: Limits {
            dt_inertia: None,
            max_wall_seconds: opts.max_wall,
        },
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
    let rows: Vec<Row> = record
        .points
        .iter()
        .map(|p| read_row(&p.id, &p.values, &dir.join("points").join(&p.id)))
        .collect();
    let written = write_table_and_figures(dir, &record, &rows)?;
    Ok(Collected { rows, written })
}

/// Redraws the figures of `DIR` from `DIR/sweep.csv` (and the design in `sweep.json`);
/// `quantity` is the column of the heat map or line plot (default: penetration depth).
pub fn plot(dir: &Path, quantity: Option<&str>) -> Result<Vec<PathBuf>, SweepError> {
    let (record, rows) = load_table(dir)?;
    check_quantity(quantity)?;
    Ok(plots::draw(dir, &record, &rows, quantity)?)
}

/// `--quantity`'s column, if given, is one of sweep.csv's.
fn check_quantity(quantity: Option<&str>) -> Result<(), SweepError> {
    match quantity {
        Some(q) if !table::quantities().contains(&q) => Err(SweepError::Input(format!(
            "--quantity {q}: not a column of sweep.csv; one of {}",
            table::quantities().join(", ")
        ))),
        _ => Ok(()),
    }
}

/// A sweep directory's `sweep.json` and the rows of its `sweep.csv` (whose axes must be
/// the record's).
fn load_table(dir: &Path) -> Result<(Record, Vec<Row>), SweepError> {
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
    Ok((record, rows))
}

/// The pillar geometry of each point of a sweep, from the overrides `sweep.json` records
/// for it (the axes', the variants' and the derived ones), the base case's where a field
/// is not overridden (the base as `sweep.json` names it, relative to the working
/// directory): (width, spacing, on the `Gap` lattice) \[µm\]; `None` for a point on a flat
/// substrate or whose base cannot be read.
fn pillar_geometry(record: &Record) -> Vec<plots::PillarGeometry> {
    record
        .points
        .iter()
        .map(|p| {
            let overrides: Vec<Override> =
                p.overrides.iter().filter_map(|o| o.parse().ok()).collect();
            let case = Case::load_with_overrides(&record.base, &overrides).ok()?;
            match &case.substrate {
                Substrate::Pillars(q) => Some((
                    q.width,
                    q.spacing,
                    q.lattice == crate::physics::Lattice::Gap,
                )),
                Substrate::Flat(_) => None,
            }
        })
        .collect()
}

/// The figure that sets a plane-strain sweep of the pillar geometry beside a 3-D one:
/// `quantity` (default: penetration depth) against the spacing, one line per width, plane
/// strain dashed, 3-D solid, the 3-D cell on the `Gap` lattice dotted with triangles;
/// written to `out`. Each sweep's points are read from its `sweep.csv`, their width,
/// spacing and lattice from its `sweep.json` (`pillar_geometry`).
pub fn plane_and_3d(
    plane: &Path,
    three_d: &Path,
    out: &Path,
    quantity: Option<&str>,
) -> Result<PathBuf, SweepError> {
    check_quantity(quantity)?;
    let q = quantity.unwrap_or("penetration_depth");
    let mut sets = Vec::new();
    for (dir, dim) in [(plane, 2), (three_d, 3)] {
        let (record, rows) = load_table(dir)?;
        let geometry = pillar_geometry(&record);
        if geometry.iter().all(Option::is_none) {
            return Err(SweepError::Input(format!(
                "{}: no point on pillars whose geometry could be read (is its base case, {}, \
                 readable from here?)",
                dir.display(),
                record.base
            )));
        }
        sets.push((dim, rows, geometry));
    }
    let curves = plots::geometry_curves(&sets, q);
    plots::by_spacing(out, &curves, q)?;
    Ok(out.to_path_buf())
}

/// What [`difference`] found: the figure and table written, and the largest difference.
#[derive(Debug, Clone)]
pub struct Difference {
    /// `diff-<quantity>.png` and `diff-<quantity>.csv`.
    pub written: Vec<PathBuf>,
    /// Points finished in both sweeps, and in all.
    pub compared: (usize, usize),
    /// The largest |b − a| over the points finished in both: (id, a, b).
    pub largest: Option<(String, f64, f64)>,
}

/// The difference of `quantity` (default: penetration depth) between two sweeps over the
/// same Grid of two axes (a map and the same map on a refined mesh, say): point by point
/// `b − a`, drawn as a heat map (`diff-<quantity>.png`: crossed where either run stopped
/// early, at the last values written) and listed in `diff-<quantity>.csv` (the id, the axes'
/// values, both statuses and values, b − a and (b − a)/|a|), both written into `out`.
pub fn difference(
    a: &Path,
    b: &Path,
    out: &Path,
    quantity: Option<&str>,
) -> Result<Difference, SweepError> {
    check_quantity(quantity)?;
    let q = quantity.unwrap_or("penetration_depth");
    let (ra, rows_a) = load_table(a)?;
    let (rb, rows_b) = load_table(b)?;
    let grid = |r: &Record| {
        (r.design.kind == design::Kind::Grid && r.design.axes.len() == 2).then(|| {
            r.design
                .axes
                .iter()
                .map(|x| (x.path.clone(), x.values.clone()))
                .collect::<Vec<_>>()
        })
    };
    match (grid(&ra), grid(&rb)) {
        (Some(ga), Some(gb)) if ga == gb => {}
        (Some(_), Some(_)) => {
            return Err(SweepError::Input(format!(
                "{} and {}: the two sweeps' axes or their values differ",
                a.display(),
                b.display()
            )));
        }
        _ => {
            return Err(SweepError::Input(format!(
                "{} and {}: a difference map needs two sweeps over the same Grid of two axes",
                a.display(),
                b.display()
            )));
        }
    }
    let partner = |r: &Row| rows_a.iter().find(|x| x.values == r.values);
    let both = |r: &Row| {
        let x = partner(r)?;
        Some((x.quantity(q)?, r.quantity(q)?))
    };
    // A point is as finished as the less finished of its two runs.
    let rows: Vec<Row> = rows_b
        .iter()
        .map(|r| {
            let mut d = r.clone();
            if let Some(x) = partner(r)
                && x.status != Status::Finished
            {
                d.status = x.status;
                d.stopped = x.stopped.clone();
            }
            d
        })
        .collect();
    let value = |r: &Row| both(r).map(|(x, y)| y - x);
    let shown = plots::Shown {
        value: &value,
        label: format!(
            "difference, {} − {}",
            b.file_name()
                .map_or(String::new(), |n| n.to_string_lossy().into()),
            a.file_name()
                .map_or(String::new(), |n| n.to_string_lossy().into())
        ),
    };
    std::fs::create_dir_all(out)
        .map_err(|e| SweepError::Input(format!("{}: {e}", out.display())))?;
    let png = out.join(format!("diff-{q}.png"));
    let name = format!("{} − {}: {q}", rb.name, ra.name);
    plots::heat_map_of(&png, &rb, &rows, &shown, &name)?;
    let mut csv = format!(
        "id,{},status_a,status_b,{q}_a,{q}_b,difference,relative\n",
        rb.axes().join(",")
    );
    let mut largest: Option<(String, f64, f64)> = None;
    let mut compared = 0;
    for r in &rows_b {
        let x = partner(r);
        let (va, vb) = (x.and_then(|x| x.quantity(q)), r.quantity(q));
        let cell = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
        let diff = va.zip(vb).map(|(x, y)| y - x);
        let rel = va.zip(diff).map(|(x, d)| d / x.abs());
        csv += &format!(
            "{},{},{},{},{},{},{},{}\n",
            r.id,
            r.values
                .iter()
                .map(|v| table::field(v))
                .collect::<Vec<_>>()
                .join(","),
            x.map_or("missing", |x| x.status.as_str()),
            r.status.as_str(),
            cell(va),
            cell(vb),
            cell(diff),
            cell(rel)
        );
        if let (Some(x), Some((va, vb))) = (x, va.zip(vb))
            && x.status == Status::Finished
            && r.status == Status::Finished
        {
            compared += 1;
            if largest
                .as_ref()
                .is_none_or(|l| (vb - va).abs() > (l.2 - l.1).abs())
            {
                largest = Some((r.id.clone(), va, vb));
            }
        }
    }
    let csv_path = out.join(format!("diff-{q}.csv"));
    std::fs::write(&csv_path, csv)
        .map_err(|e| SweepError::Input(format!("{}: {e}", csv_path.display())))?;
    Ok(Difference {
        written: vec![png, csv_path],
        compared: (compared, rows_b.len()),
        largest,
    })
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

    #[test]
    fn a_difference_map_finds_the_point_that_moved() {
        // The committed pillar-geometry map against a copy of it in which one point's
        // penetration depth moved by 0.25 µm and another stopped early.
        let dir = std::env::temp_dir().join(format!("cellsim-sweep-diff-{}", std::process::id()));
        let (a, b) = (dir.join("a"), dir.join("b"));
        for d in [&a, &b] {
            std::fs::create_dir_all(d).unwrap();
            for f in ["sweep.json", "sweep.csv"] {
                std::fs::copy(repo("plots/sweeps/pillar-geometry").join(f), d.join(f)).unwrap();
            }
        }
        let (axes, mut rows) =
            table::parse(&std::fs::read_to_string(b.join("sweep.csv")).unwrap()).unwrap();
        let moved = rows[7].penetration.unwrap() + 0.25;
        rows[7].penetration = Some(moved);
        rows[3].status = Status::Failed;
        std::fs::write(b.join("sweep.csv"), table::render(&axes, &rows)).unwrap();
        let d = difference(&a, &b, &dir, None).unwrap();
        assert_eq!(d.compared, (24, 25));
        let (id, x, y) = d.largest.unwrap();
        assert_eq!((id.as_str(), y), (rows[7].id.as_str(), moved));
        assert!((y - x - 0.25).abs() < 1e-12);
        let csv = std::fs::read_to_string(dir.join("diff-penetration_depth.csv")).unwrap();
        assert_eq!(csv.lines().count(), 26);
        assert!(csv.lines().nth(4).unwrap().contains(",finished,failed,"));
        assert!(dir.join("diff-penetration_depth.png").exists());
        // Sweeps over other axes are refused.
        let other = repo("plots/sweeps/contractility");
        assert!(difference(&a, &other, &dir, None).is_err());
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
        use crate::render::paper::REPORTED;
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
                    crate::render::paper::Quantity::NucleusDisplacement(
                        crate::render::paper::When::GravityEnd
                            | crate::render::paper::When::SpreadingEnd
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
