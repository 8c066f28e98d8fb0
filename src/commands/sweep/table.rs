//! `sweep.csv`: one row per point, and the penetration depth derived from a run.
//!
//! Columns: `id`, one per axis (its dotted path; the value the point has on that axis),
//! `status` (finished / failed / invalid / interrupted / missing), the last row of the
//! point's `timeseries.csv` (its columns [`COLUMNS`], `t` … `uy_nucleus_max`: the final
//! values of a finished run, the last ones written for one that stopped),
//! `penetration_depth` (µm), `wall_seconds` (set-up and integration), `steps`, the stop of
//! a point that did not finish as fields ([`Stopped`]: `stop_class`, `t_stop`,
//! `stop_element`, `stop_x`, `stop_y`, `stop_z`) and `reason` (why the point failed, is
//! invalid or interrupted, in words).
//! Numbers are written in full precision; fields with a comma or a quote are quoted as
//! RFC 4180 says.

use crate::case::{Case, Substrate};
use crate::model::observables::{COLUMNS, N_COLUMNS};
use crate::run_files::Observables;

/// What became of a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// The run reached its end time.
    Finished,
    /// The run stopped early: integration failure, step limit, stall, wall budget.
    Failed,
    /// The point's case is not valid (its validation message is the reason).
    Invalid,
    /// A signal stopped the run.
    Interrupted,
    /// Not run (yet): another shard's, or the sweep was stopped before it started.
    Missing,
}

impl Status {
    /// The word in the `status` column.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Finished => "finished",
            Status::Failed => "failed",
            Status::Invalid => "invalid",
            Status::Interrupted => "interrupted",
            Status::Missing => "missing",
        }
    }

    fn parse(s: &str) -> Option<Status> {
        Some(match s {
            "finished" => Status::Finished,
            "failed" => Status::Failed,
            "invalid" => Status::Invalid,
            "interrupted" => Status::Interrupted,
            "missing" => Status::Missing,
            _ => return None,
        })
    }
}

/// One row of `sweep.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Point id.
    pub id: String,
    /// The point's value on each axis (RON text).
    pub values: Vec<String>,
    /// What became of it.
    pub status: Status,
    /// The last output row written, if any.
    pub last: Option<Observables>,
    /// How far the nucleus bottom went below the pillar tops at the last output \[µm\].
    pub penetration: Option<f64>,
    /// Wall seconds of set-up and integration.
    pub wall_seconds: Option<f64>,
    /// Integrator steps.
    pub steps: Option<u64>,
    /// How a point that did not finish stopped, as fields.
    pub stopped: Stopped,
    /// Further final values: [`EXTRA_COLUMNS`], in order (the contact areas of a 3-D run,
    /// the largest nucleus strain); `None` where the run or its cellsim has none.
    pub extras: [Option<f64>; 3],
    /// When the adhesion and active phases started, for a run whose cell starts them
    /// itself (MODEL.md §11): [`EVENT_COLUMNS`] (`None` for a run on the paper's clock; a
    /// start not reached is `Some(None)`).
    pub events: Option<[Option<f64>; 2]>,
    /// Why the point failed, is invalid or was interrupted (one line).
    pub reason: String,
}

/// The phase starts of [`Row::events`], after the further values, in a sweep whose points
/// start phases on conditions.
pub const EVENT_COLUMNS: [&str; 2] = ["t_adhesion_start", "t_active_start"];

/// The further final values of [`Row::extras`], after the stop's columns: the deformed and
/// reference contact areas of a 3-D run (whole cell \[µm²\]) and the largest ‖E‖_F at a
/// quadrature point of the nucleus.
pub const EXTRA_COLUMNS: [&str; 3] = ["contact_area", "contact_area_ref", "strain_nucleus_max"];

/// How a point stopped, as fields a map can draw: the class (the summary's failure kind:
/// `stalled`, `inverted`, `step_limit`, `budget`, `interrupted`, `integration`, …; or
/// `invalid`), the time the run reached, and for an inverted element which element and
/// where it was (its centroid; `z` only in 3-D). Empty for a finished point.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Stopped {
    /// The class (`stop_class`).
    pub class: String,
    /// Simulated time reached \[s\] (`t_stop`).
    pub t: Option<f64>,
    /// The element (`stop_element`).
    pub element: Option<usize>,
    /// Its centroid \[µm\] (`stop_x`, `stop_y`, `stop_z`).
    pub x: [Option<f64>; 3],
}

impl Stopped {
    /// What a point's status alone says: the class `invalid` or `interrupted` for those,
    /// nothing otherwise (a failed run's class comes from its summary).
    pub fn of_status(status: Status) -> Self {
        Stopped {
            class: match status {
                Status::Invalid | Status::Interrupted => status.as_str().into(),
                _ => String::new(),
            },
            ..Stopped::default()
        }
    }
}

/// The columns of [`Stopped`], in order.
const STOP_COLUMNS: [&str; 6] = [
    "stop_class",
    "t_stop",
    "stop_element",
    "stop_x",
    "stop_y",
    "stop_z",
];

impl Row {
    /// A row with only an id, values, a status and a reason.
    pub fn bare(id: &str, values: Vec<String>, status: Status, reason: &str) -> Row {
        Row {
            id: id.to_string(),
            values,
            status,
            last: None,
            penetration: None,
            wall_seconds: None,
            steps: None,
            stopped: Stopped::of_status(status),
            extras: [None; 3],
            events: None,
            reason: one_line(reason),
        }
    }

    /// The value of a numeric column by name: a timeseries column, `penetration_depth`,
    /// `wall_seconds` or `steps`.
    pub fn quantity(&self, name: &str) -> Option<f64> {
        match name {
            "penetration_depth" => self.penetration,
            "wall_seconds" => self.wall_seconds,
            "steps" => self.steps.map(|s| s as f64),
            _ => match EXTRA_COLUMNS.iter().position(|c| *c == name) {
                Some(k) => self.extras[k],
                None => match EVENT_COLUMNS.iter().position(|c| *c == name) {
                    Some(k) => self.events.and_then(|e| e[k]),
                    None => self.last.and_then(|o| o.get(name)),
                },
            },
        }
    }
}

/// The numeric columns a figure can show.
pub fn quantities() -> Vec<&'static str> {
    let mut q: Vec<&str> = COLUMNS[1..].to_vec();
    q.extend(["penetration_depth", "wall_seconds", "steps"]);
    q.extend(EXTRA_COLUMNS);
    q.extend(EVENT_COLUMNS);
    q
}

/// Joins the lines of a message with "; ".
pub fn one_line(s: &str) -> String {
    s.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

/// How far the nucleus bottom p_b is below the pillar tops \[µm\], 0 when above them or on
/// a flat substrate:
///
/// depth = max(0, y_top − (c_y − r_n + u_y(p_b)))
///
/// with c_y − r_n the reference height of p_b (the lowest point of the nucleus, on the
/// symmetry line) and y_top the height of the pillar tops ([`crate::case::Pillars::resolved_y_top`]).
pub fn penetration_depth(case: &Case, uy_bottom: f64) -> f64 {
    match &case.substrate {
        Substrate::Flat(_) => 0.0,
        Substrate::Pillars(p) => {
            let y_top = p.resolved_y_top(&case.geometry);
            let y_b = case.geometry.centre_y - case.geometry.r_n + uy_bottom;
            (y_top - y_b).max(0.0)
        }
    }
}

/// A CSV field, quoted when it holds a comma, a quote or a line break.
pub(crate) fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn num(v: Option<f64>) -> String {
    v.map(|x| x.to_string()).unwrap_or_default()
}

/// The header line for `axes`, with the [`EVENT_COLUMNS`] when `events`.
pub fn header(axes: &[String], events: bool) -> String {
    let mut cols: Vec<String> = vec!["id".into()];
    cols.extend(axes.iter().map(|a| field(a)));
    cols.push("status".into());
    cols.extend(COLUMNS.iter().map(|c| c.to_string()));
    cols.extend([
        "penetration_depth".into(),
        "wall_seconds".into(),
        "steps".into(),
    ]);
    cols.extend(STOP_COLUMNS.iter().map(|c| c.to_string()));
    cols.extend(EXTRA_COLUMNS.iter().map(|c| c.to_string()));
    if events {
        cols.extend(EVENT_COLUMNS.iter().map(|c| c.to_string()));
    }
    cols.push("reason".into());
    cols.join(",")
}

/// One row's line, with the [`EVENT_COLUMNS`] when `events`.
pub fn line(r: &Row, events: bool) -> String {
    let mut cols: Vec<String> = vec![field(&r.id)];
    cols.extend(r.values.iter().map(|v| field(v)));
    cols.push(r.status.as_str().into());
    match r.last {
        Some(o) => cols.extend(o.values().iter().map(|v| v.to_string())),
        None => cols.extend((0..N_COLUMNS).map(|_| String::new())),
    }
    cols.push(num(r.penetration));
    cols.push(num(r.wall_seconds));
    cols.push(r.steps.map(|s| s.to_string()).unwrap_or_default());
    let s = &r.stopped;
    cols.push(field(&s.class));
    cols.push(num(s.t));
    cols.push(s.element.map(|e| e.to_string()).unwrap_or_default());
    cols.extend(s.x.iter().map(|&v| num(v)));
    cols.extend(r.extras.iter().map(|&v| num(v)));
    if events {
        let e = r.events.unwrap_or([None; 2]);
        cols.extend(e.iter().map(|&v| num(v)));
    }
    cols.push(field(&r.reason));
    cols.join(",")
}

/// The whole file (with the [`EVENT_COLUMNS`] when some row has events).
pub fn render(axes: &[String], rows: &[Row]) -> String {
    let events = rows.iter().any(|r| r.events.is_some());
    let mut s = header(axes, events);
    s.push('\n');
    for r in rows {
        s.push_str(&line(r, events));
        s.push('\n');
    }
    s
}

/// Splits one CSV line into fields (RFC 4180 quoting; no line breaks inside fields).
fn split(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', true) => quoted = false,
            ('"', false) if cur.is_empty() => quoted = true,
            (',', false) => out.push(std::mem::take(&mut cur)),
            (c, _) => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// What is wrong with a `sweep.csv`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CsvError {
    /// No header.
    #[error("empty file (no header)")]
    Empty,
    /// A line (counted from 1) is wrong.
    #[error("line {line}: {problem}")]
    Line {
        /// The line.
        line: usize,
        /// What is wrong.
        problem: String,
    },
}

/// Parses `sweep.csv`: the axis paths and the rows. The error names the line.
pub fn parse(text: &str) -> Result<(Vec<String>, Vec<Row>), CsvError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, head) = lines.next().ok_or(CsvError::Empty)?;
    let head = split(head);
    let header = |problem: String| CsvError::Line { line: 1, problem };
    let status_at = head
        .iter()
        .position(|h| h == "status")
        .ok_or_else(|| header("no `status` column".into()))?;
    if head.first().map(String::as_str) != Some("id") {
        return Err(header("the first column is not `id`".into()));
    }
    let axes: Vec<String> = head[1..status_at].to_vec();
    let has_events = head.iter().any(|h| h == EVENT_COLUMNS[0]);
    let n_events = if has_events { EVENT_COLUMNS.len() } else { 0 };
    let expected =
        status_at + 1 + N_COLUMNS + 4 + STOP_COLUMNS.len() + EXTRA_COLUMNS.len() + n_events;
    // Written before the further values, or before the stop's fields too: read with
    // those empty.
    let without_extras = expected - n_events - EXTRA_COLUMNS.len();
    let without_stop = without_extras - STOP_COLUMNS.len();
    let has_extras = head.len() == expected;
    let has_stop = has_extras || head.len() == without_extras;
    if !has_stop && head.len() != without_stop {
        let older = !head.iter().any(|h| h == COLUMNS[N_COLUMNS - 1]);
        return Err(header(format!(
            "{} columns, expected {expected}{}",
            head.len(),
            if older {
                format!(
                    " (no `{}` column: a sweep.csv of an older cellsim, whose \
                     strain_cytoplasm excluded the membrane; run the sweep again)",
                    COLUMNS[N_COLUMNS - 1]
                )
            } else {
                String::new()
            }
        )));
    }
    let mut rows = Vec::new();
    for (k, l) in lines {
        let f = split(l);
        let bad = |problem: String| CsvError::Line {
            line: k + 1,
            problem,
        };
        if f.len() != head.len() {
            return Err(bad(format!("{} fields, expected {}", f.len(), head.len())));
        }
        let number = |s: &str| -> Result<Option<f64>, CsvError> {
            if s.is_empty() {
                Ok(None)
            } else {
                s.parse()
                    .map(Some)
                    .map_err(|_| bad(format!("`{s}` is not a number")))
            }
        };
        let status = Status::parse(&f[status_at])
            .ok_or_else(|| bad(format!("unknown status `{}`", f[status_at])))?;
        let obs = &f[status_at + 1..status_at + 1 + N_COLUMNS];
        let last = if obs.iter().all(|s| s.is_empty()) {
            None
        } else {
            let mut v = [0.0; N_COLUMNS];
            for (x, s) in v.iter_mut().zip(obs) {
                *x = number(s)?.unwrap_or(f64::NAN);
            }
            Some(Observables::from_values(v))
        };
        let rest = &f[status_at + 1 + N_COLUMNS..];
        rows.push(Row {
            id: f[0].clone(),
            values: f[1..status_at].to_vec(),
            status,
            last,
            penetration: number(&rest[0])?,
            wall_seconds: number(&rest[1])?,
            steps: number(&rest[2])?.map(|s| s as u64),
            stopped: if has_stop {
                let element = match rest[5].as_str() {
                    "" => None,
                    e => Some(
                        e.parse()
                            .map_err(|_| bad(format!("`{e}` is not an element index")))?,
                    ),
                };
                Stopped {
                    class: rest[3].clone(),
                    t: number(&rest[4])?,
                    element,
                    x: [number(&rest[6])?, number(&rest[7])?, number(&rest[8])?],
                }
            } else {
                Stopped::default()
            },
            extras: if has_extras {
                [number(&rest[9])?, number(&rest[10])?, number(&rest[11])?]
            } else {
                [None; 3]
            },
            events: if has_events {
                Some([number(&rest[12])?, number(&rest[13])?])
            } else {
                None
            },
            reason: rest[rest.len() - 1].clone(),
        });
    }
    Ok((axes, rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_round_trip_through_the_csv_text() {
        let axes = vec![
            "substrate.width".to_string(),
            "active.pac.inner_semi_axes".into(),
        ];
        let rows = vec![
            Row {
                id: "g0_1".into(),
                values: vec!["6.0".into(), "(5.0, 4.0)".into()],
                status: Status::Finished,
                last: Some(Observables::from_values([
                    600.0, 8.4, -6.6, -3.0, -5.5, 0.2, 0.5, 6.1, 0.7, -6.9,
                ])),
                penetration: Some(1.25),
                wall_seconds: Some(3.5),
                steps: Some(775),
                stopped: Stopped::default(),
                extras: [Some(817.9), Some(620.5), Some(1.31)],
                events: None,
                reason: String::new(),
            },
            Row {
                id: "g0_2".into(),
                values: vec!["7.0".into(), "(5.0, 4.0)".into()],
                status: Status::Failed,
                last: None,
                penetration: None,
                wall_seconds: Some(9.0),
                steps: Some(90),
                stopped: Stopped {
                    class: "inverted".into(),
                    t: Some(48276.14),
                    element: Some(246),
                    x: [Some(6.2), Some(-4.1), None],
                },
                extras: [None, None, Some(0.42)],
                events: None,
                reason: "element 246, contact point 35: det F = -2.4e-5".into(),
            },
            Row::bare(
                "g1_0",
                vec!["8.0".into(), "(5.0, 4.0)".into()],
                Status::Invalid,
                "base.ron:3:4: x = 1 is \"bad\", really\nsecond line",
            ),
        ];
        let text = render(&axes, &rows);
        assert!(text.starts_with(
            "id,substrate.width,active.pac.inner_semi_axes,status,t,contact_radius,uy_top,"
        ));
        let (a, r) = parse(&text).unwrap();
        assert_eq!(a, axes);
        assert_eq!(r, rows);
        assert_eq!(
            r[2].reason,
            "base.ron:3:4: x = 1 is \"bad\", really; second line"
        );
        assert_eq!(r[0].quantity("uy_top"), Some(-6.6));
        assert_eq!(r[0].quantity("penetration_depth"), Some(1.25));
        // The paper's measures are columns too, read by name.
        assert_eq!(r[0].quantity("contact_radius_ref"), Some(6.1));
        assert_eq!(r[0].quantity("strain_membrane"), Some(0.7));
        assert_eq!(r[0].quantity("uy_nucleus_max"), Some(-6.9));
        for q in ["contact_radius_ref", "strain_membrane", "uy_nucleus_max"] {
            assert!(quantities().contains(&q), "{q}");
        }
        // The further values too.
        assert_eq!(r[0].quantity("contact_area"), Some(817.9));
        assert_eq!(r[0].quantity("strain_nucleus_max"), Some(1.31));
        assert_eq!(r[1].quantity("contact_area"), None);
        for q in EXTRA_COLUMNS {
            assert!(quantities().contains(&q), "{q}");
        }
        assert!(parse("id,status\n").is_err());
        // A sweep.csv written before those columns existed: refused, saying why.
        let old = "id,status,t,contact_radius,uy_top,uy_centre,uy_bottom,strain_nucleus,\
                   strain_cytoplasm,penetration_depth,wall_seconds,steps,reason\n";
        let err = parse(old).unwrap_err().to_string();
        assert!(err.contains("older cellsim"), "{err}");
        // One written before the further values (and before the stop's fields too):
        // read, those fields empty.
        let without = |dropped: usize| {
            let lines: Vec<String> = text
                .lines()
                .map(|l| {
                    let mut f = split(l);
                    let n = f.len();
                    f.drain(n - 1 - dropped..n - 1);
                    f.iter().map(|s| field(s)).collect::<Vec<_>>().join(",")
                })
                .collect();
            parse(&lines.join("\n")).unwrap().1
        };
        let r = without(EXTRA_COLUMNS.len());
        assert_eq!(r[1].stopped, rows[1].stopped);
        assert_eq!(r[0].extras, [None; 3]);
        assert_eq!(r[1].reason, rows[1].reason);
        let r = without(EXTRA_COLUMNS.len() + STOP_COLUMNS.len());
        assert_eq!(r[1].stopped, Stopped::default());
        assert_eq!(r[1].reason, rows[1].reason);
        assert_eq!(r[1].steps, Some(90));
    }

    #[test]
    fn phase_starts_are_columns_when_a_row_has_them() {
        let axes = vec!["phases.adhesion_start".to_string()];
        let mut rows = vec![
            Row::bare("g0", vec!["Settled(1e-5)".into()], Status::Finished, ""),
            Row::bare(
                "g1",
                vec!["Settled(1e-6)".into()],
                Status::Failed,
                "no event",
            ),
        ];
        rows[0].events = Some([Some(5580.8), Some(21993.2)]);
        rows[1].events = Some([Some(9049.0), None]);
        let text = render(&axes, &rows);
        assert!(
            text.lines()
                .next()
                .unwrap()
                .ends_with(",t_adhesion_start,t_active_start,reason")
        );
        let (_, r) = parse(&text).unwrap();
        assert_eq!(r, rows);
        assert_eq!(r[0].quantity("t_active_start"), Some(21993.2));
        assert_eq!(r[1].quantity("t_active_start"), None);
        assert!(quantities().contains(&"t_adhesion_start"));
        // Without events, no such columns.
        for r in &mut rows {
            r.events = None;
        }
        assert!(!render(&axes, &rows).contains("t_adhesion_start"));
    }

    #[test]
    fn penetration_depth_counts_from_the_pillar_tops() {
        let mut case = Case::new("p", Substrate::pillars(), 1.0);
        let p = match &case.substrate {
            Substrate::Pillars(p) => p.clone(),
            Substrate::Flat(_) => unreachable!(),
        };
        let y_top = p.resolved_y_top(&case.geometry);
        // p_b starts at c_y - r_n = 3.5 µm; 3.5 + u = y_top - 2 is 2 µm below the tops.
        let u = y_top - 2.0 - 3.5;
        assert!((penetration_depth(&case, u) - 2.0).abs() < 1e-12);
        assert_eq!(penetration_depth(&case, -1.0), 0.0);
        case.substrate = Substrate::flat();
        assert_eq!(penetration_depth(&case, -8.0), 0.0);
    }
}
