//! The comparison table of a sweep: its points against values reported elsewhere (a
//! paper), written as markdown (`DIR/table.md`) and CSV (`DIR/table.csv`) from the point
//! directories, and optionally spliced into markdown documents between two markers.
//!
//! The sweep file's optional `table` section describes it, for a Grid of two axes: one
//! axis gives the rows (e.g. the readings of a paper), the other what each column is
//! measured on (e.g. the scenes):
//!
//! ```ron
//! table: (
//!     rows: "reading",                 // the row axis; the other axis is the columns'
//!     reference: "paper",              // label of the row of reported values
//!     groups: [(title: "Flat substrate", columns: [
//!         (key: "flat_r_end", label: "contact radius at 40 000 s (µm)", of: "flat",
//!          quantity: "contact_radius_ref", at: End, reference: 8.8, score: true),
//!     ])],
//!     summary: ["flat_r_end"],         // columns of the short table
//!     documents: [(path: "../../docs/fidelity.md", part: Full)],  // relative to the sweep file
//! )
//! ```
//!
//! A column's value is a `timeseries.csv` column of the point (row value, `of`) at a time
//! (`at`: the phase ends, the end, a time, or the largest or smallest value over the run),
//! multiplied by `scale`; with `minus`, the same of the point (row value, `minus`) is
//! subtracted, and `abs` takes the absolute value. A cell is the value, `=` when the
//! point's case is the first row's (the row's overrides leave that case unchanged), or
//! says why there is none (failed before that time, invalid, not run). The closeness table
//! gives, for the `score` columns, (value − reference)/reference and the mean of its
//! absolute value over them. A document receives the `Full` tables or the `Summary`
//! between the lines `<!-- cellsim sweep NAME: begin -->` and
//! `<!-- cellsim sweep NAME: end -->`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::design::{Design, Kind};
use super::table::{Row, Status};
use super::{Record, SweepError};
use crate::case::Case;
use crate::model::observables::{COLUMNS, interpolate};
use crate::run_files::Observables;

/// When a column's value is taken.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum At {
    /// At the run's end time t_end (default).
    #[default]
    End,
    /// At T_g0, the end of the gravity ramp.
    GravityEnd,
    /// At T_as0, the end of the adhesion ramp.
    SpreadingEnd,
    /// At T_a0, the end of the active-strain ramp.
    ActiveEnd,
    /// At a time \[s\].
    Time(f64),
    /// The largest scaled value over the run (needs a finished run).
    Largest,
    /// The smallest scaled value over the run (needs a finished run).
    Smallest,
}

/// One column of the table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Column {
    /// Short unique key (the column of `table.csv`, and how `summary` names it).
    pub key: String,
    /// Header in the markdown table.
    pub label: String,
    /// Shorter header for the closeness and summary tables (default: `label`).
    #[serde(
        default,
        deserialize_with = "super::present",
        skip_serializing_if = "Option::is_none"
    )]
    pub short: Option<String>,
    /// The value of the column axis measured.
    pub of: String,
    /// A `timeseries.csv` column.
    pub quantity: String,
    /// When.
    #[serde(default)]
    pub at: At,
    /// Factor applied to the value (e.g. −1 for a downward displacement, 100 for %).
    #[serde(default = "one")]
    pub scale: f64,
    /// A value of the column axis whose value (same quantity, time and scale) is
    /// subtracted.
    #[serde(
        default,
        deserialize_with = "super::present",
        skip_serializing_if = "Option::is_none"
    )]
    pub minus: Option<String>,
    /// Take the absolute value (after `minus`).
    #[serde(default)]
    pub abs: bool,
    /// The reported value, in the column's (scaled) unit.
    #[serde(
        default,
        deserialize_with = "super::present",
        skip_serializing_if = "Option::is_none"
    )]
    pub reference: Option<f64>,
    /// Counted in the closeness table (needs `reference`).
    #[serde(default)]
    pub score: bool,
    /// Decimals shown.
    #[serde(default = "two")]
    pub digits: usize,
}

/// Columns shown together, one markdown table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Group {
    /// Heading of the table.
    pub title: String,
    /// Its columns.
    pub columns: Vec<Column>,
}

/// What a document receives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Part {
    /// Every table: the groups, the closeness, the rows' overrides, the points that did
    /// not finish.
    #[default]
    Full,
    /// The short table (the `summary` columns with their differences, and the mean).
    Summary,
}

/// A markdown document that receives a part of the table between its markers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Document {
    /// The file; in the sweep file relative to it, in `sweep.json` as resolved.
    pub path: String,
    /// What it receives.
    #[serde(default)]
    pub part: Part,
}

/// The `table` section of a sweep file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableSpec {
    /// The axis whose values are the rows; the other axis is what columns are `of`.
    pub rows: String,
    /// Label of the row of reported values.
    #[serde(default = "default_reference")]
    pub reference: String,
    /// The column groups.
    pub groups: Vec<Group>,
    /// Keys of the columns of the short table.
    #[serde(default)]
    pub summary: Vec<String>,
    /// Documents that receive the table.
    #[serde(default)]
    pub documents: Vec<Document>,
}

fn one() -> f64 {
    1.0
}

fn two() -> usize {
    2
}

fn default_reference() -> String {
    "reference".into()
}

impl Column {
    fn short(&self) -> &str {
        self.short.as_deref().unwrap_or(&self.label)
    }
}

/// The begin and end markers of sweep `name`'s block in a document.
pub fn markers(name: &str) -> (String, String) {
    (
        format!("<!-- cellsim sweep {name}: begin -->"),
        format!("<!-- cellsim sweep {name}: end -->"),
    )
}

/// What is wrong with a document's markers ([`markers`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MarkerError {
    /// The begin or the end marker is missing or given more than once.
    #[error("needs the line `{begin}` once and then the line `{end}` once")]
    Count {
        /// The begin marker.
        begin: String,
        /// The end marker.
        end: String,
    },
    /// The end marker comes first.
    #[error("`{end}` comes before `{begin}`")]
    Order {
        /// The begin marker.
        begin: String,
        /// The end marker.
        end: String,
    },
}

/// Why a sweep's `table` does not fit its design or its documents.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TableSpecError {
    /// The design is not a Grid of two axes.
    #[error("table: needs a Grid of two axes (rows and columns)")]
    NotAGrid,
    /// `rows` names no axis.
    #[error("table: rows = {0:?} is not an axis")]
    Rows(String),
    /// A group has no columns, or there is no group.
    #[error("table: no columns (every group needs one)")]
    NoColumns,
    /// A column is wrong.
    #[error("table: column `{key}`: {problem}")]
    Column {
        /// The column's key.
        key: String,
        /// What is wrong.
        problem: String,
    },
    /// `summary` names no column.
    #[error("table: summary names `{0}`, which is no column's key")]
    Summary(String),
    /// A document cannot be read or its markers are wrong.
    #[error("table: document {path}: {problem}")]
    Document {
        /// The document.
        path: String,
        /// What is wrong.
        problem: String,
    },
}

/// `text` with the block between the markers replaced by `block`; the error says what
/// is wrong with the markers.
pub fn splice(text: &str, name: &str, block: &str) -> Result<String, MarkerError> {
    let (begin, end) = markers(name);
    let count = |m: &str| text.lines().filter(|l| l.trim() == m).count();
    if count(&begin) != 1 || count(&end) != 1 {
        return Err(MarkerError::Count { begin, end });
    }
    let b = text.find(&begin).unwrap_or(0);
    let e = text.find(&end).unwrap_or(0);
    if e < b {
        return Err(MarkerError::Order { begin, end });
    }
    let head = &text[..b + begin.len()];
    let tail = &text[e..];
    Ok(format!("{head}\n{}\n{tail}", block.trim_end()))
}

impl TableSpec {
    /// Every column, in order.
    pub fn columns(&self) -> impl Iterator<Item = &Column> {
        self.groups.iter().flat_map(|g| g.columns.iter())
    }

    /// Checks the table against the design; resolves the documents' paths against
    /// `dir` (the sweep file's directory) and checks their markers.
    pub fn resolve(
        mut self,
        design: &Design,
        name: &str,
        dir: &Path,
    ) -> Result<Self, TableSpecError> {
        if design.kind != Kind::Grid || design.axes.len() != 2 {
            return Err(TableSpecError::NotAGrid);
        }
        let Some(r) = design.axes.iter().position(|a| a.path == self.rows) else {
            return Err(TableSpecError::Rows(self.rows));
        };
        let other = &design.axes[1 - r];
        if self.groups.is_empty() || self.groups.iter().any(|g| g.columns.is_empty()) {
            return Err(TableSpecError::NoColumns);
        }
        let mut keys: Vec<&str> = Vec::new();
        for c in self.columns() {
            let bad = |problem: String| {
                Err(TableSpecError::Column {
                    key: c.key.clone(),
                    problem,
                })
            };
            if c.key.trim().is_empty() || c.key.contains([',', '"', '\n']) {
                return bad("key must be one word (no comma or quote)".into());
            }
            if keys.contains(&c.key.as_str()) {
                return bad("key given twice".into());
            }
            keys.push(&c.key);
            for v in std::iter::once(&c.of).chain(&c.minus) {
                if !other.values.contains(v) {
                    return bad(format!(
                        "{v:?} is not a value of axis `{}` ({})",
                        other.path,
                        other.values.join(", ")
                    ));
                }
            }
            if !COLUMNS[1..].contains(&c.quantity.as_str()) {
                return bad(format!(
                    "quantity {:?} is not a column of timeseries.csv ({})",
                    c.quantity,
                    COLUMNS[1..].join(", ")
                ));
            }
            if !c.scale.is_finite() || c.digits > 10 {
                return bad("scale must be finite and digits at most 10".into());
            }
            if let At::Time(t) = c.at {
                if !(t.is_finite() && t >= 0.0) {
                    return bad(format!("Time({t}) must be a finite time >= 0"));
                }
            }
            if c.score && c.reference.is_none_or(|v| v == 0.0 || !v.is_finite()) {
                return bad("score needs a finite, nonzero reference".into());
            }
        }
        if let Some(k) = self.summary.iter().find(|k| !keys.contains(&k.as_str())) {
            return Err(TableSpecError::Summary(k.clone()));
        }
        for d in &mut self.documents {
            let path = dir.join(&d.path);
            let bad = |problem: String| TableSpecError::Document {
                path: path.display().to_string(),
                problem,
            };
            let text = std::fs::read_to_string(&path).map_err(|e| bad(e.to_string()))?;
            splice(&text, name, "").map_err(|m| bad(m.to_string()))?;
            d.path = path.display().to_string();
        }
        Ok(self)
    }
}

/// A table cell.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// The value, and whether the point's case (and the `minus` point's) is the first
    /// row's.
    Value(f64, bool),
    /// No value: why (one short phrase).
    None(String),
}

impl Cell {
    fn value(&self) -> Option<f64> {
        match self {
            Cell::Value(v, _) => Some(*v),
            Cell::None(_) => None,
        }
    }
}

/// What the table reads of one point.
#[derive(Debug, Clone, Default)]
pub struct PointData {
    /// Id.
    pub id: String,
    /// Status and reason (from `sweep.csv`'s row).
    pub status: Option<Status>,
    /// Why it did not finish.
    pub reason: String,
    /// The resolved case's text.
    pub case_text: Option<String>,
    /// Phase times T_g0, T_as0, T_a0, t_end.
    pub phases: Option<[f64; 4]>,
    /// The time series.
    pub series: Vec<Observables>,
}

impl PointData {
    /// Reads a point's directory (`row` gives its status).
    pub fn load(dir: &Path, row: &Row) -> PointData {
        let case_text = std::fs::read_to_string(dir.join("case.ron")).ok();
        let phases = case_text
            .as_deref()
            .and_then(|t| Case::from_str(t, "case.ron").ok())
            .map(|c| [c.phases.t_g0, c.phases.t_as0, c.phases.t_a0, c.phases.t_end]);
        let csv = dir.join("timeseries.csv");
        let series = std::fs::read_to_string(&csv)
            .ok()
            .and_then(|t| crate::run_files::read::parse_timeseries(&csv, &t).ok())
            .map(|(s, _)| s)
            .unwrap_or_default();
        PointData {
            id: row.id.clone(),
            status: Some(row.status),
            reason: row.reason.clone(),
            case_text,
            phases,
            series,
        }
    }

    /// The scaled value of `c` (without `minus`/`abs`), or why there is none.
    fn value(&self, c: &Column) -> Result<f64, String> {
        let status = self.status.unwrap_or(Status::Missing);
        match status {
            Status::Invalid => return Err("invalid".into()),
            Status::Missing => return Err("not run".into()),
            _ => {}
        }
        let t_last = self.series.last().map_or(0.0, |o| o.t);
        let stopped = || {
            let what = if status == Status::Interrupted {
                "interrupted"
            } else {
                "failed"
            };
            format!("{what} at t = {} s", fmt_time(t_last))
        };
        let get = |o: &Observables| o.get(&c.quantity).map(|v| v * c.scale);
        let [tg, tas, ta, t_end] = self.phases.ok_or("no case.ron")?;
        let t = match c.at {
            At::Largest | At::Smallest => {
                if status != Status::Finished {
                    return Err(stopped());
                }
                let vals = self.series.iter().filter_map(get);
                let v = if c.at == At::Largest {
                    vals.fold(f64::NEG_INFINITY, f64::max)
                } else {
                    vals.fold(f64::INFINITY, f64::min)
                };
                return if v.is_finite() {
                    Ok(v)
                } else {
                    Err("no data".into())
                };
            }
            At::End => t_end,
            At::GravityEnd => tg,
            At::SpreadingEnd => tas,
            At::ActiveEnd => ta,
            At::Time(t) => t,
        };
        if t > t_end * (1.0 + 1e-12) {
            return Err(format!("ends before t = {} s", fmt_time(t)));
        }
        match interpolate(&self.series, t).and_then(|o| get(&o)) {
            Some(v) => Ok(v),
            None if status == Status::Finished => Err("no data".into()),
            None => Err(stopped()),
        }
    }
}

fn fmt_time(t: f64) -> String {
    // Thousands separated by a thin space, as the README writes times.
    let s = format!("{:.0}", t.max(0.0));
    let n = s.len();
    let mut out = String::new();
    for (k, ch) in s.chars().enumerate() {
        if k > 0 && (n - k) % 3 == 0 {
            out.push('\u{202f}');
        }
        out.push(ch);
    }
    out
}

/// The computed table: row labels, and per row one cell per column (in
/// [`TableSpec::columns`] order).
#[derive(Debug, Clone, PartialEq)]
pub struct Computed {
    /// Row labels (the row axis's values, in order).
    pub rows: Vec<String>,
    /// Cells.
    pub cells: Vec<Vec<Cell>>,
    /// Points that did not finish: id, row, column value, status and reason.
    pub unfinished: Vec<(String, String, String, Status, String)>,
}

/// Computes the table from the points' data: `point(row, of)` gives a point's data.
pub fn compute(
    spec: &TableSpec,
    design: &Design,
    point: &dyn Fn(&str, &str) -> Option<PointData>,
) -> Computed {
    let r = design
        .axes
        .iter()
        .position(|a| a.path == spec.rows)
        .unwrap_or(0);
    let rows = design.axes[r].values.clone();
    let others = &design.axes[1 - r].values;
    let first = rows.first().cloned().unwrap_or_default();
    let mut cells = Vec::new();
    for row in &rows {
        let mut line = Vec::new();
        for c in spec.columns() {
            let cell = (|| {
                let p = point(row, &c.of).ok_or("not run")?;
                let mut v = p.value(c)?;
                let mut same = row != &first && same_case(&p, point(&first, &c.of).as_ref());
                if let Some(m) = &c.minus {
                    let q = point(row, m).ok_or("not run")?;
                    v -= q.value(c).map_err(|e| format!("{m}: {e}"))?;
                    same = same && same_case(&q, point(&first, m).as_ref());
                }
                if c.abs {
                    v = v.abs();
                }
                Ok::<_, String>(Cell::Value(v, same))
            })();
            line.push(cell.unwrap_or_else(Cell::None));
        }
        cells.push(line);
    }
    let mut unfinished = Vec::new();
    for row in &rows {
        for of in others {
            if let Some(p) = point(row, of) {
                let s = p.status.unwrap_or(Status::Missing);
                if s != Status::Finished {
                    unfinished.push((p.id.clone(), row.clone(), of.clone(), s, p.reason));
                }
            }
        }
    }
    Computed {
        rows,
        cells,
        unfinished,
    }
}

fn same_case(p: &PointData, first: Option<&PointData>) -> bool {
    match (&p.case_text, first.and_then(|f| f.case_text.as_ref())) {
        (Some(a), Some(b)) => a == b,
        _ => false,
    }
}

fn fmt(v: f64, digits: usize) -> String {
    let s = format!("{v:.digits$}");
    // No "-0.00".
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s.replace('-', "−")
    }
}

fn fmt_cell(c: &Cell, digits: usize) -> String {
    match c {
        Cell::Value(_, true) => "=".into(),
        Cell::Value(v, false) => fmt(*v, digits),
        Cell::None(why) => why.clone(),
    }
}

fn percent(d: f64) -> String {
    let s = format!("{:+.0} %", 100.0 * d);
    if s == "-0 %" || s == "+0 %" {
        "0 %".into()
    } else {
        s.replace('-', "−")
    }
}

fn md(s: &str) -> String {
    s.replace('|', "\\|")
}

/// The relative differences of a row's scored cells, and their mean absolute value with
/// how many there were.
fn closeness(spec: &TableSpec, line: &[Cell]) -> (Vec<Option<f64>>, Option<(f64, usize)>) {
    let d: Vec<Option<f64>> = spec
        .columns()
        .zip(line)
        .filter(|(c, _)| c.score)
        .map(|(c, cell)| Some((cell.value()? - c.reference?) / c.reference?))
        .collect();
    let got: Vec<f64> = d.iter().flatten().map(|x| x.abs()).collect();
    let mean = (!got.is_empty()).then(|| (got.iter().sum::<f64>() / got.len() as f64, got.len()));
    (d, mean)
}

fn fmt_mean(m: Option<(f64, usize)>, n: usize) -> String {
    match m {
        Some((v, k)) if k == n => format!("{:.0} %", 100.0 * v),
        Some((v, k)) => format!("{:.0} % ({k} of {n})", 100.0 * v),
        None => "–".into(),
    }
}

/// The closeness table (markdown).
fn closeness_table(spec: &TableSpec, t: &Computed) -> String {
    let scored: Vec<&Column> = spec.columns().filter(|c| c.score).collect();
    if scored.is_empty() {
        return String::new();
    }
    let mut s = String::new();
    let _ = write!(s, "| {} |", md(&spec.rows));
    for c in &scored {
        let _ = write!(s, " {} |", md(c.short()));
    }
    s += " mean \\|Δ\\| |\n|---|";
    s += &"---:|".repeat(scored.len() + 1);
    s += "\n";
    for (row, line) in t.rows.iter().zip(&t.cells) {
        let (d, mean) = closeness(spec, line);
        let _ = write!(s, "| {} |", md(row));
        for x in &d {
            let _ = write!(s, " {} |", x.map_or("–".into(), percent));
        }
        let _ = writeln!(s, " {} |", fmt_mean(mean, scored.len()));
    }
    s
}

/// The `Full` part: a table per group, the closeness, the rows' overrides, the points
/// that did not finish.
pub fn full_markdown(record: &Record, spec: &TableSpec, t: &Computed, source: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "_Generated by `cellsim sweep` (cellsim {}) from `{source}`; regenerate with \
         `cellsim sweep {} --out {source}`. Do not edit by hand._\n",
        record.cellsim_version, record.sweep_file
    );
    let _ = writeln!(
        s,
        "Each row takes MODEL.md's defaults except what its overrides change (listed \
         below). `=`: the row's overrides leave that scene's case unchanged, so the value \
         is the first row's.\n"
    );
    let mut k0 = 0;
    for g in &spec.groups {
        let _ = writeln!(s, "**{}**\n", md(&g.title));
        let _ = write!(s, "| {} |", md(&spec.rows));
        for c in &g.columns {
            let _ = write!(s, " {} |", md(&c.label));
        }
        s += "\n|---|";
        s += &"---:|".repeat(g.columns.len());
        s += "\n";
        if g.columns.iter().any(|c| c.reference.is_some()) {
            let _ = write!(s, "| **{}** |", md(&spec.reference));
            for c in &g.columns {
                let v = c.reference.map(|v| format!("**{}**", fmt(v, c.digits)));
                let _ = write!(s, " {} |", v.unwrap_or_default());
            }
            s += "\n";
        }
        for (row, line) in t.rows.iter().zip(&t.cells) {
            let _ = write!(s, "| {} |", md(row));
            for (c, cell) in g.columns.iter().zip(&line[k0..]) {
                let _ = write!(s, " {} |", md(&fmt_cell(cell, c.digits)));
            }
            s += "\n";
        }
        s += "\n";
        k0 += g.columns.len();
    }
    let close = closeness_table(spec, t);
    if !close.is_empty() {
        let _ = writeln!(
            s,
            "**Closeness to the {}**: Δ = (value − {0})/{0} for the columns with a \
             reported value that count (the {0}'s own measure), and the mean of |Δ| over \
             them.\n",
            md(&spec.reference)
        );
        s += &close;
        s += "\n";
    }
    let _ = writeln!(s, "**Overrides of each row**\n");
    let _ = writeln!(s, "| {} | overrides |\n|---|---|", md(&spec.rows));
    if let Some(axis) = record.design.axes.iter().find(|a| a.path == spec.rows) {
        for v in &axis.values {
            let set = axis.variant_set(v).map(|s| s.to_vec()).unwrap_or_else(|| {
                if axis.is_variants() {
                    Vec::new()
                } else {
                    vec![format!("{}={v}", axis.path)]
                }
            });
            let text = if set.is_empty() {
                "none".to_string()
            } else {
                set.iter()
                    .map(|o| format!("`{}`", md(o)))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let _ = writeln!(s, "| {} | {text} |", md(v));
        }
    }
    s += "\n";
    if t.unfinished.is_empty() {
        let _ = writeln!(s, "Every point finished.");
    } else {
        let _ = writeln!(s, "**Points that did not finish**\n");
        for (id, row, of, status, reason) in &t.unfinished {
            let _ = writeln!(
                s,
                "- `{id}` ({}, {}): {}{}",
                md(row),
                md(of),
                status.as_str(),
                if reason.is_empty() {
                    String::new()
                } else {
                    format!(": {}", md(reason))
                }
            );
        }
    }
    s
}

/// The `Summary` part: the summary columns, each value with its difference to the
/// reference, and the mean |Δ| of the closeness table.
pub fn summary_markdown(spec: &TableSpec, t: &Computed, source: &str) -> String {
    let cols: Vec<(usize, &Column)> = spec
        .summary
        .iter()
        .filter_map(|k| spec.columns().enumerate().find(|(_, c)| &c.key == k))
        .collect();
    let n_scored = spec.columns().filter(|c| c.score).count();
    let mut s = String::new();
    let _ = write!(s, "| {} |", md(&spec.rows));
    for (_, c) in &cols {
        let _ = write!(s, " {} |", md(c.short()));
    }
    if n_scored > 0 {
        s += " mean \\|Δ\\| |";
    }
    s += "\n|---|";
    s += &"---:|".repeat(cols.len() + usize::from(n_scored > 0));
    s += "\n";
    let _ = write!(s, "| **{}** |", md(&spec.reference));
    for (_, c) in &cols {
        let v = c.reference.map(|v| format!("**{}**", fmt(v, c.digits)));
        let _ = write!(s, " {} |", v.unwrap_or_default());
    }
    if n_scored > 0 {
        s += " |";
    }
    s += "\n";
    for (row, line) in t.rows.iter().zip(&t.cells) {
        let _ = write!(s, "| {} |", md(row));
        for (k, c) in &cols {
            let cell = &line[*k];
            let text = match (cell, c.reference) {
                (Cell::Value(v, _), Some(r)) if r != 0.0 => {
                    format!("{} ({})", fmt(*v, c.digits), percent((v - r) / r))
                }
                (Cell::Value(v, _), _) => fmt(*v, c.digits),
                (Cell::None(why), _) => why.clone(),
            };
            let _ = write!(s, " {} |", md(&text));
        }
        if n_scored > 0 {
            let (_, mean) = closeness(spec, line);
            let _ = write!(s, " {} |", fmt_mean(mean, n_scored));
        }
        s += "\n";
    }
    let _ = writeln!(
        s,
        "\n_Generated by `cellsim sweep` from `{source}` (values, and in parentheses \
         (value − {0})/{0}); do not edit by hand._",
        md(&spec.reference)
    );
    s
}

/// `table.csv`: a row per table row (the reference first), a column per key, full
/// precision, empty where there is no value.
pub fn csv(spec: &TableSpec, t: &Computed) -> String {
    let field = |s: &str| {
        if s.contains([',', '"', '\n']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_string()
        }
    };
    let mut s = field(&spec.rows);
    for c in spec.columns() {
        s += ",";
        s += &c.key;
    }
    s += "\n";
    s += &field(&spec.reference);
    for c in spec.columns() {
        s += ",";
        s += &c.reference.map(|v| v.to_string()).unwrap_or_default();
    }
    s += "\n";
    for (row, line) in t.rows.iter().zip(&t.cells) {
        s += &field(row);
        for cell in line {
            s += ",";
            s += &cell.value().map(|v| v.to_string()).unwrap_or_default();
        }
        s += "\n";
    }
    s
}

/// Writes `DIR/table.md` and `DIR/table.csv` from the point directories and splices the
/// parts into the documents; returns the files written. Nothing without a `table`.
pub fn write(dir: &Path, record: &Record, rows: &[Row]) -> Result<Vec<PathBuf>, SweepError> {
    let Some(spec) = &record.table else {
        return Ok(Vec::new());
    };
    let r = record
        .design
        .axes
        .iter()
        .position(|a| a.path == spec.rows)
        .unwrap_or(0);
    let point = |row: &str, of: &str| -> Option<PointData> {
        let k = record.points.iter().position(|p| {
            p.values.get(r).map(String::as_str) == Some(row)
                && p.values.get(1 - r).map(String::as_str) == Some(of)
        })?;
        let id = &record.points[k].id;
        let row = rows.iter().find(|x| &x.id == id)?;
        Some(PointData::load(&dir.join("points").join(id), row))
    };
    let t = compute(spec, &record.design, &point);
    let source = dir.display().to_string();
    let full = full_markdown(record, spec, &t, &source);
    let mut written = Vec::new();
    let md_path = dir.join("table.md");
    let title = format!("# {}: the table\n\n", record.name);
    super::write_atomic(&md_path, &(title + &full))?;
    written.push(md_path);
    let csv_path = dir.join("table.csv");
    super::write_atomic(&csv_path, &csv(spec, &t))?;
    written.push(csv_path);
    for d in &spec.documents {
        let path = PathBuf::from(&d.path);
        let text = std::fs::read_to_string(&path).map_err(SweepError::io(&path))?;
        let block = match d.part {
            Part::Full => full.clone(),
            Part::Summary => summary_markdown(spec, &t, &source),
        };
        let new = splice(&text, &record.name, &block)
            .map_err(|m| SweepError::Input(format!("{}: {m}", path.display())))?;
        if new != text {
            super::write_atomic(&path, &new)?;
        }
        written.push(path);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::Substrate;
    use crate::commands::sweep::design::DesignSpec;
    use crate::commands::sweep::{RecordPoint, Settings};

    /// The record of the sweep "t" of `design` with `points` and the table `table`.
    fn record(design: Design, points: Vec<RecordPoint>, table: TableSpec) -> Record {
        Record {
            name: "t".into(),
            sweep_file: "t.ron".into(),
            base: "b.ron".into(),
            design,
            set: vec![],
            derive: vec![],
            points,
            settings: Settings {
                jobs: 1,
                retry_failed: false,
                max_wall: None,
                shards: None,
            },
            cellsim_version: "0".into(),
            table: Some(table),
        }
    }

    fn design() -> Design {
        let spec: DesignSpec = ron::Options::default()
            .from_str(
                r#"Grid([
                    (name: "reading", variants: [(name: "base", set: []), (name: "stiff", set: ["materials.gamma=0.5"])]),
                    (name: "scene", variants: [(name: "a", set: []), (name: "b", set: ["phases.t_end=300.0"])]),
                ])"#,
            )
            .unwrap();
        Design::from_spec(&spec).unwrap()
    }

    fn spec(text: &str) -> TableSpec {
        ron::Options::default().from_str(text).unwrap()
    }

    const SPEC: &str = r#"(
        rows: "reading",
        reference: "paper",
        groups: [(title: "G", columns: [
            (key: "r_g", label: "radius at T_g0", of: "a", quantity: "contact_radius", at: GravityEnd, reference: 2.0, score: true),
            (key: "d_max", label: "largest down", of: "a", quantity: "uy_top", at: Largest, scale: -1.0, reference: 4.0, score: true, digits: 1),
            (key: "diff", label: "b - a", of: "b", minus: "a", quantity: "uy_top", at: Time(150.0), abs: true, digits: 3),
        ])],
        summary: ["d_max"],
    )"#;

    /// A point's data: phases (T_g0 = 100 s, ..., t_end) and rows (t, contact radius,
    /// uy_top).
    fn data(
        id: &str,
        status: Status,
        case: &str,
        t_end: f64,
        rows: &[(f64, f64, f64)],
    ) -> PointData {
        PointData {
            id: id.into(),
            status: Some(status),
            reason: if status == Status::Finished {
                String::new()
            } else {
                "IDA_CONV_FAIL".into()
            },
            case_text: Some(case.into()),
            phases: Some([100.0, 200.0, 250.0, t_end]),
            series: rows
                .iter()
                .map(|&(t, r, u)| {
                    let mut v = [0.0; crate::model::observables::N_COLUMNS];
                    v[0] = t;
                    v[1] = r;
                    v[2] = u;
                    Observables::from_values(v)
                })
                .collect(),
        }
    }

    fn points(row: &str, of: &str) -> Option<PointData> {
        let series = [
            (0.0, 0.0, 0.0),
            (100.0, 1.0, -1.0),
            (200.0, 3.0, -5.0),
            (250.0, 3.0, -4.0),
        ];
        Some(match (row, of) {
            ("base", "a") => data("g0_0", Status::Finished, "A", 250.0, &series),
            ("base", "b") => data(
                "g0_1",
                Status::Finished,
                "B",
                300.0,
                &[(0.0, 0.0, 0.0), (300.0, 0.0, -2.0)],
            ),
            // The first row's case: a value, shown as "=".
            ("stiff", "a") => data("g1_0", Status::Finished, "A", 250.0, &series),
            // Stopped at t = 120 s: values up to then only.
            ("stiff", "b") => data(
                "g1_1",
                Status::Failed,
                "B2",
                300.0,
                &[(0.0, 0.0, 0.0), (120.0, 0.5, -1.5)],
            ),
            _ => return None,
        })
    }

    #[test]
    fn cells_are_values_at_their_times_or_say_why_not() {
        let d = design();
        let s = spec(SPEC).resolve(&d, "t", Path::new(".")).unwrap();
        let t = compute(&s, &d, &points);
        assert_eq!(t.rows, ["base", "stiff"]);
        // Base: radius at T_g0 = 100 s; the largest of −uy_top; |uy_b − uy_a| at 150 s
        // (b interpolated: −1, a: −3).
        assert_eq!(
            t.cells[0],
            [
                Cell::Value(1.0, false),
                Cell::Value(5.0, false),
                Cell::Value(2.0, false)
            ]
        );
        // Stiff: same case as the first row on `a` (=); b failed at 120 s, before 150 s.
        assert_eq!(t.cells[1][0], Cell::Value(1.0, true));
        assert_eq!(t.cells[1][2], Cell::None("failed at t = 120 s".into()));
        assert_eq!(t.unfinished.len(), 1);
        assert_eq!(t.unfinished[0].0, "g1_1");
        // The markdown says the same, with the paper's row, the closeness and the
        // overrides.
        let record = record(d.clone(), vec![], s.clone());
        let md = full_markdown(&record, &s, &t, "out");
        assert!(
            md.contains("| reading | radius at T_g0 | largest down | b - a |"),
            "{md}"
        );
        assert!(md.contains("| **paper** | **2.00** | **4.0** |  |"), "{md}");
        assert!(md.contains("| base | 1.00 | 5.0 | 2.000 |"), "{md}");
        assert!(
            md.contains("| stiff | = | = | failed at t = 120 s |"),
            "{md}"
        );
        // Closeness: (1 − 2)/2 = −50 %, (5 − 4)/4 = +25 %, mean 38 %.
        assert!(md.contains("| base | −50 % | +25 % | 38 % |"), "{md}");
        assert!(md.contains("| stiff | `materials.gamma=0.5` |"), "{md}");
        assert!(
            md.contains("- `g1_1` (stiff, b): failed: IDA_CONV_FAIL"),
            "{md}"
        );
        let sm = summary_markdown(&s, &t, "out");
        assert!(sm.contains("| base | 5.0 (+25 %) | 38 % |"), "{sm}");
        let c = csv(&s, &t);
        assert_eq!(
            c.lines().collect::<Vec<_>>(),
            [
                "reading,r_g,d_max,diff",
                "paper,2,4,",
                "base,1,5,2",
                "stiff,1,5,"
            ]
        );
    }

    #[test]
    fn a_table_that_does_not_fit_the_design_is_refused() {
        let d = design();
        let err = |text: &str| {
            spec(text)
                .resolve(&d, "t", Path::new("."))
                .unwrap_err()
                .to_string()
        };
        let one =
            |col: &str| format!(r#"(rows: "reading", groups: [(title: "G", columns: [{col}])])"#);
        assert!(
            err(&one(
                r#"(key: "k", label: "l", of: "c", quantity: "uy_top")"#
            ))
            .contains("\"c\" is not a value of axis `scene`")
        );
        assert!(
            err(&one(r#"(key: "k", label: "l", of: "a", quantity: "uy")"#))
                .contains("not a column of timeseries.csv")
        );
        assert!(
            err(&one(
                r#"(key: "k", label: "l", of: "a", quantity: "uy_top", score: true)"#
            ))
            .contains("score needs")
        );
        assert!(
            err(&one(
                r#"(key: "k", label: "l", of: "a", minus: "z", quantity: "uy_top")"#
            ))
            .contains("\"z\"")
        );
        assert!(err(r#"(rows: "scene2", groups: [])"#).contains("not an axis"));
        assert!(err(r#"(rows: "reading", groups: [])"#).contains("no columns"));
        let two = one(
            r#"(key: "k", label: "l", of: "a", quantity: "uy_top"), (key: "k", label: "m", of: "b", quantity: "uy_top")"#,
        );
        assert!(err(&two).contains("key given twice"));
        let mut s = spec(&one(
            r#"(key: "k", label: "l", of: "a", quantity: "uy_top")"#,
        ));
        s.summary = vec!["nope".into()];
        assert!(
            s.clone()
                .resolve(&d, "t", Path::new("."))
                .unwrap_err()
                .to_string()
                .contains("summary names `nope`")
        );
        s.summary.clear();
        s.documents = vec![Document {
            path: "no-such-document.md".into(),
            part: Part::Full,
        }];
        assert!(
            s.resolve(&d, "t", Path::new("."))
                .unwrap_err()
                .to_string()
                .contains("no-such-document.md")
        );
        // Only a Grid of two axes has rows and columns.
        let spec1: DesignSpec = ron::Options::default()
            .from_str(r#"Grid([(path: "materials.gamma", values: [0.1])])"#)
            .unwrap();
        let d1 = Design::from_spec(&spec1).unwrap();
        let e = spec(SPEC).resolve(&d1, "t", Path::new(".")).unwrap_err();
        assert!(e.to_string().contains("Grid of two axes"), "{e}");
    }

    #[test]
    fn documents_receive_the_block_between_their_markers_only() {
        let text = "# Doc\nbefore\n<!-- cellsim sweep s: begin -->\nold\nlines\n<!-- cellsim sweep s: end -->\nafter\n";
        let new = splice(text, "s", "| new |\n").unwrap();
        assert_eq!(
            new,
            "# Doc\nbefore\n<!-- cellsim sweep s: begin -->\n| new |\n<!-- cellsim sweep s: end -->\nafter\n"
        );
        assert_eq!(splice(&new, "s", "| new |").unwrap(), new);
        assert!(splice(text, "other", "x").is_err());
        let twice = format!("{text}<!-- cellsim sweep s: begin -->\n");
        assert!(splice(&twice, "s", "x").is_err());
        let reversed = "<!-- cellsim sweep s: end -->\n<!-- cellsim sweep s: begin -->\n";
        assert!(
            splice(reversed, "s", "x")
                .unwrap_err()
                .to_string()
                .contains("before")
        );
    }

    #[test]
    fn write_reads_the_point_directories_and_fills_the_documents() {
        let dir = std::env::temp_dir().join(format!("cellsim-compare-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let doc = dir.join("doc.md");
        std::fs::write(
            &doc,
            "x\n<!-- cellsim sweep t: begin -->\n<!-- cellsim sweep t: end -->\ny\n",
        )
        .unwrap();
        let d = design();
        let mut s = spec(SPEC);
        s.documents = vec![Document {
            path: "doc.md".into(),
            part: Part::Summary,
        }];
        let s = s.resolve(&d, "t", &dir).unwrap();
        let case = |t_end: f64| {
            let mut c = Case::new("c", Substrate::flat(), t_end);
            (c.phases.t_g0, c.phases.t_as0, c.phases.t_a0) = (100.0, 200.0, 250.0);
            c.to_ron().unwrap()
        };
        let header = Observables::CSV_HEADER;
        let ids = [
            ("g0_0", 250.0),
            ("g0_1", 300.0),
            ("g1_0", 250.0),
            ("g1_1", 300.0),
        ];
        let mut rows = Vec::new();
        let mut points = Vec::new();
        for (k, (id, t_end)) in ids.iter().enumerate() {
            let p = dir.join("points").join(id);
            std::fs::create_dir_all(&p).unwrap();
            std::fs::write(p.join("case.ron"), case(*t_end)).unwrap();
            let u = -(k as f64) - 1.0;
            std::fs::write(
                p.join("timeseries.csv"),
                format!("{header}\n0,0,0,0,0,0,0,0,0,0\n{t_end},1,{u},0,0,0,0,0,0,0\n"),
            )
            .unwrap();
            let values = vec![
                d.axes[0].values[k / 2].clone(),
                d.axes[1].values[k % 2].clone(),
            ];
            rows.push(Row::bare(id, values.clone(), Status::Finished, ""));
            points.push(RecordPoint {
                id: id.to_string(),
                values,
                overrides: vec![],
            });
        }
        let record = record(d, points, s);
        let written = write(&dir, &record, &rows).unwrap();
        assert_eq!(written.len(), 3);
        let csv = std::fs::read_to_string(dir.join("table.csv")).unwrap();
        // Largest of −uy_top on `a`: 1 (base), 3 (stiff); `diff` at 150 s: |−1 − (−0.6)|
        // = 0.4 (base) and |−2 − (−1.8)| = 0.2 (stiff); radius at T_g0 = 100 s: 0.4.
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[2], "base,0.4,1,0.4", "{csv}");
        assert!(lines[3].starts_with("stiff,0.4,3,0.2"), "{csv}");
        let text = std::fs::read_to_string(&doc).unwrap();
        assert!(
            text.starts_with("x\n<!-- cellsim sweep t: begin -->\n| reading | largest down | mean"),
            "{text}"
        );
        assert!(text.contains("| stiff | 3.0 (−25 %) |"), "{text}");
        assert!(
            text.ends_with("<!-- cellsim sweep t: end -->\ny\n"),
            "{text}"
        );
        assert!(
            std::fs::read_to_string(dir.join("table.md"))
                .unwrap()
                .contains("**G**")
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
