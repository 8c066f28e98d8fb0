//! The time plots of the 2-D cell's runs (they serve the 3-D cell's runs too, whose
//! timeseries.csv has the same columns): the [`TimePlot`] — curves, reported values, the
//! phases T_g0, T_as0, T_a0 marked and named, notes where runs are the same run — and how
//! it is drawn ([`draw_time_plot`], [`time_figure`]); the paper's time figures built on
//! it: the contact radius ([`contact_radius_figure`], Fig. 6b), the nucleus displacement
//! with its panel of maxima ([`displacement_figure`], Fig. 9's kind of curve), the strain
//! norms ([`strain_time_figure`]) and the upside-down experiment ([`upside_down_figure`]),
//! each with the paper's reported values as hollow circles. What it may import of
//! [`super`]: [`super::draw`] and [`super::scenes`] (a run's phases), and the error types
//! and [`super::draw_png`] of [`super`].

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

use super::draw::{
    Chart, Curve, FONT, LEGEND_GLYPH, MarkShape, Marks, PALETTE, Stroke, TIME_SIZE,
    UPSIDE_DOWN_SIZE, anchored_text, column_label, draw_curve, draw_marks, group_thousands,
};
use super::scenes::run_phases;
use super::{DrawError, OutputError, draw_png};
use crate::run_files::{Observables, RunData};

/// A note over a time interval, drawn as a bracket under the row of phase names: e.g.
/// where several runs are the same run.
#[derive(Debug, Clone, PartialEq)]
pub struct SpanNote {
    /// Start of the interval \[s\].
    pub from: f64,
    /// End of the interval \[s\].
    pub to: f64,
    /// Text above the bracket.
    pub text: String,
}

/// A time plot: curves, reported values and the phases.
#[derive(Debug, Clone)]
pub struct TimePlot {
    /// Title above the plot.
    pub title: String,
    /// y-axis description, with units.
    pub y_desc: String,
    /// The curves.
    pub curves: Vec<Curve>,
    /// Reported values, and ours where they are compared.
    pub marks: Vec<Marks>,
    /// Thin vertical lines joining a paper value to the cellsim value it is compared with:
    /// (t, one value, the other).
    pub links: Vec<(f64, f64, f64)>,
    /// Notes over time intervals (brackets under the phase names).
    pub notes: Vec<SpanNote>,
    /// The value axis starts at 0 (for quantities that cannot be negative), unless a value
    /// is negative.
    pub from_zero: bool,
    /// T_g0, T_as0, T_a0 and the end time \[s\]: boundaries are drawn at the first three
    /// where they lie inside the time axis.
    pub phase_times: [f64; 4],
    /// Name of the interval after T_a0, if shown ("rest", "gravity flipped", …).
    pub after_active: String,
    /// Right end of the time axis \[s\].
    pub t_max: f64,
    /// Where the legend goes.
    pub legend: SeriesLabelPosition,
}

/// The finite values of the curves and marks of `plot`.
fn plot_values(plot: &TimePlot) -> impl Iterator<Item = f64> + '_ {
    plot.curves
        .iter()
        .flat_map(|c| c.points.iter())
        .chain(plot.marks.iter().flat_map(|m| m.points.iter()))
        .map(|p| p.1)
        .filter(|v| v.is_finite())
}

/// The value axis for values `vals`: padded by 8 % of their span below and, to leave room
/// for the phase names (and the notes, `notes` of them), 16 % (+ 10 % per note) above. With
/// `from_zero` and no negative value the axis starts at exactly 0. A unit range if there is
/// nothing.
pub fn value_axis(vals: impl Iterator<Item = f64>, from_zero: bool, notes: usize) -> (f64, f64) {
    let (lo, hi) = vals
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !(lo <= hi) {
        return (0.0, 1.0);
    }
    let zero = from_zero && lo >= 0.0;
    let lo = if zero { 0.0 } else { lo };
    let span = (hi - lo).max(1e-6 * hi.abs().max(lo.abs())).max(1e-12);
    let top = 0.16 + 0.10 * notes as f64;
    let bottom = if zero { 0.0 } else { lo - 0.08 * span };
    (bottom, hi + top * span)
}

/// The value axis of a time plot (see [`value_axis`]).
pub fn value_range(plot: &TimePlot) -> (f64, f64) {
    value_axis(plot_values(plot), plot.from_zero, plot.notes.len())
}

/// The last output time up to which every run of `runs` wrote the same rows (every column
/// equal to 1e-12 relative), or `None` with fewer than two runs or rows that differ from
/// the first. Rows are compared in order; the runs must share their output times.
pub fn identical_until(runs: &[&RunData]) -> Option<f64> {
    let (first, rest) = runs.split_first()?;
    if rest.is_empty() {
        return None;
    }
    let same = |a: f64, b: f64| a == b || (a - b).abs() <= 1e-12 * a.abs().max(b.abs());
    let mut until = None;
    for (k, row) in first.series.iter().enumerate() {
        let all = rest.iter().all(|r| {
            r.series.get(k).is_some_and(|o| {
                row.values()
                    .iter()
                    .zip(o.values().iter())
                    .all(|(a, b)| same(*a, *b))
            })
        });
        if !all {
            break;
        }
        until = Some(row.t);
    }
    until
}

/// A note saying that `runs` are the same run until [`identical_until`], naming the phase
/// boundary it falls on (`who` names the runs). `None` if they differ from the start, are
/// fewer than two, or stay identical to the end of the shortest.
pub fn identical_note(runs: &[&RunData], who: &str) -> Option<SpanNote> {
    let until = identical_until(runs)?;
    let shortest = runs
        .iter()
        .map(|r| r.t_last())
        .fold(f64::INFINITY, f64::min);
    if until <= 0.0 {
        return None;
    }
    let names = ["T_g0", "T_as0", "T_a0"];
    let [tg, tas, ta, _] = runs[0].mesh.phase_times;
    let at = [tg, tas, ta]
        .iter()
        .zip(names)
        .find(|(t, _)| **t == until)
        .map(|(_, n)| format!(" = {n}"))
        .unwrap_or_default();
    let text = if until >= shortest {
        format!("{who}: identical runs throughout")
    } else {
        format!(
            "{who}: identical runs until t = {} s{at} (one curve)",
            group_thousands(until)
        )
    };
    Some(SpanNote {
        from: 0.0,
        to: until,
        text,
    })
}

fn phase_intervals(plot: &TimePlot) -> Vec<(f64, f64, String)> {
    let [tg, tas, ta, _] = plot.phase_times;
    let names = ["gravity", "spreading", "active", plot.after_active.as_str()];
    let bounds = [0.0, tg, tas, ta, f64::INFINITY];
    let mut out = Vec::new();
    for k in 0..4 {
        let (a, b) = (bounds[k], bounds[k + 1].min(plot.t_max));
        if b > a && a < plot.t_max && !names[k].is_empty() {
            out.push((a, b, names[k].to_string()));
        }
    }
    out
}

/// Margin around a time plot \[px\].
const TIME_MARGIN: u32 = 18;
/// Height of the time axis' label area \[px\].
const TIME_X_LABELS: u32 = 60;

/// Draws a time plot into `area` on its own value axis ([`value_range`]).
pub fn draw_time_plot<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    plot: &TimePlot,
) -> Result<(), DrawError> {
    draw_time_plot_on(area, plot, value_range(plot))
}

/// Draws a time plot into `area` with the value axis `range`. Without a title there
/// is no caption, so a panel beside it built with the same margins lines up.
pub fn draw_time_plot_on<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    plot: &TimePlot,
    range: (f64, f64),
) -> Result<(), DrawError> {
    let t_max = if plot.t_max > 0.0 { plot.t_max } else { 1.0 };
    // 3 % of room after the end, so marks at the end time are not cut.
    let t_axis_end = 1.03 * t_max;
    let mut chart = time_chart(area, &plot.title, &plot.y_desc, t_axis_end, range)?;
    draw_phases(&mut chart, plot, range)?;
    draw_notes(&mut chart, &plot.notes, range, t_max, t_axis_end)?;
    for c in &plot.curves {
        draw_curve(&mut chart, c)?;
    }
    // The lines joining the paper's values to ours, under the marks.
    chart.draw_series(plot.links.iter().map(|&(t, a, b)| {
        PathElement::new(vec![(t, a), (t, b)], RGBColor(90, 90, 90).stroke_width(2))
    }))?;
    for m in &plot.marks {
        draw_marks(&mut chart, m)?;
    }
    draw_time_legend(&mut chart, plot)
}

/// The axes of a time plot in `area`: time from 0 to `t_axis_end`, the values over
/// `(lo, hi)` described by `y_desc`, the `title` as caption unless it is empty.
fn time_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    title: &str,
    y_desc: &str,
    t_axis_end: f64,
    (lo, hi): (f64, f64),
) -> Result<Chart<'a, DB>, DrawError> {
    let mut builder = ChartBuilder::on(area);
    if !title.is_empty() {
        builder.caption(title, (FONT, 28));
    }
    let mut chart = builder
        .margin(TIME_MARGIN)
        .margin_right(44)
        .x_label_area_size(TIME_X_LABELS)
        .y_label_area_size(90)
        .build_cartesian_2d(0.0..t_axis_end, lo..hi)?;
    let fmt_t = |v: &f64| group_thousands(*v);
    chart
        .configure_mesh()
        .x_desc("time t (s)")
        .y_desc(y_desc)
        .x_label_formatter(&fmt_t)
        .axis_desc_style((FONT, 22))
        .label_style((FONT, 18))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    Ok(chart)
}

/// The phases of `plot` on the value axis `(lo, hi)`: a dashed line at each boundary
/// after 0, each phase's name centred along the top.
fn draw_phases<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    plot: &TimePlot,
    (lo, hi): (f64, f64),
) -> Result<(), DrawError> {
    let grey = RGBColor(110, 110, 110);
    for (a, b, name) in phase_intervals(plot) {
        if a > 0.0 {
            chart.draw_series(DashedLineSeries::new(
                vec![(a, lo), (a, hi)],
                8,
                6,
                grey.stroke_width(2),
            ))?;
        }
        let mid = 0.5 * (a + b);
        let style = anchored_text(18, HPos::Center, VPos::Top).color(&grey);
        chart.draw_series(std::iter::once(Text::new(
            name,
            (mid, hi - 0.01 * (hi - lo)),
            style,
        )))?;
    }
    Ok(())
}

/// The `notes` of a time plot on the value axis `(lo, hi)`: a bracket over each note's
/// interval (cut at `t_axis_end`) under the phase names, its text above it, indented by
/// 1 % of `t_max`.
fn draw_notes<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    notes: &[SpanNote],
    (lo, hi): (f64, f64),
    t_max: f64,
    t_axis_end: f64,
) -> Result<(), DrawError> {
    for (k, n) in notes.iter().enumerate() {
        let span = hi - lo;
        let y_text = hi - (0.055 + 0.09 * k as f64) * span;
        let y_line = y_text - 0.045 * span;
        let tick = 0.015 * span;
        let (a, b) = (n.from.max(0.0), n.to.min(t_axis_end));
        chart.draw_series(std::iter::once(PathElement::new(
            vec![
                (a, y_line - tick),
                (a, y_line),
                (b, y_line),
                (b, y_line - tick),
            ],
            BLACK.stroke_width(2),
        )))?;
        chart.draw_series(std::iter::once(Text::new(
            n.text.clone(),
            (a + 0.01 * t_max, y_text),
            anchored_text(18, HPos::Left, VPos::Top),
        )))?;
    }
    Ok(())
}

/// The legend of a time plot where `plot.legend` puts it.
fn draw_time_legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    plot: &TimePlot,
) -> Result<(), DrawError> {
    // Upper legends start below the row of phase names and the notes.
    let position = match plot.legend {
        SeriesLabelPosition::UpperLeft => {
            SeriesLabelPosition::Coordinate(12, 40 + 60 * plot.notes.len() as i32)
        }
        ref other => other.clone(),
    };
    chart
        .configure_series_labels()
        .position(position)
        .legend_area_size(LEGEND_GLYPH + 12)
        .margin(12)
        .label_font((FONT, 18))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// Draws a [`TimePlot`] into a PNG at `path` of [`TIME_SIZE`].
pub fn time_figure(path: &Path, plot: &TimePlot) -> Result<(), OutputError> {
    draw_png(path, TIME_SIZE, |root| draw_time_plot(root, plot))
}

/// (t, value) points of one quantity.
pub fn points(rows: &[Observables], f: impl Fn(&Observables) -> f64) -> Vec<(f64, f64)> {
    rows.iter()
        .map(|o| (o.t, f(o)))
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect()
}

/// The largest end time among `runs` (the time axis shows where partial runs stopped).
fn t_axis(runs: &[&RunData]) -> f64 {
    runs.iter().map(|r| r.t_end()).fold(0.0, f64::max)
}

/// A run's label in a legend: its name, with "(stopped at t = … s)" if it did not finish.
pub fn run_label(r: &RunData) -> String {
    if r.finished() {
        r.name.clone()
    } else {
        format!(
            "{} (stopped at t = {} s)",
            r.name,
            group_thousands(r.t_last())
        )
    }
}

/// A value the paper reports set against the cellsim value it is compared with (signed as
/// the curve it is drawn on).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Compared {
    /// Time of the cellsim value \[s\]: the time the paper gives, or when our extreme is
    /// reached.
    pub t: f64,
    /// The paper's value.
    pub paper: f64,
    /// Ours, a point of the curve it is compared with.
    pub ours: f64,
}

/// Marks, filled dots and joining lines for `compared` values: paper hollow black
/// circles, ours filled dots in `color` on the curve, a grey line between.
fn compared_marks(compared: &[Compared], color: RGBColor) -> (Vec<Marks>, Vec<(f64, f64, f64)>) {
    let marks = vec![
        Marks {
            label: String::new(),
            points: compared.iter().map(|c| (c.t, c.paper)).collect(),
            color: BLACK,
            radius: 8,
            filled: false,
            shape: MarkShape::Circle,
        },
        Marks {
            label: String::new(),
            points: compared.iter().map(|c| (c.t, c.ours)).collect(),
            color,
            radius: 6,
            filled: true,
            shape: MarkShape::Circle,
        },
    ];
    let links = compared.iter().map(|c| (c.t, c.paper, c.ours)).collect();
    (marks, links)
}

/// Legend entries (no points) for the paper's marks (`paper_label`) and for ours
/// (`ours_label`).
fn compared_legend(paper_label: &str, ours_label: &str) -> Vec<Marks> {
    vec![
        Marks {
            label: paper_label.to_string(),
            points: vec![],
            color: BLACK,
            radius: 8,
            filled: false,
            shape: MarkShape::Circle,
        },
        Marks {
            label: ours_label.to_string(),
            points: vec![],
            color: BLACK,
            radius: 6,
            filled: true,
            shape: MarkShape::Circle,
        },
    ]
}

/// The names of `runs` without their common prefix up to a `-` ("pillars-push",
/// "pillars-pull" → "push", "pull").
pub fn short_names(runs: &[&RunData]) -> Vec<String> {
    let names: Vec<&str> = runs.iter().map(|r| r.name.as_str()).collect();
    let prefix = names.first().and_then(|n| n.find('-').map(|k| &n[..=k]));
    let strip = match prefix {
        Some(p) if names.iter().all(|n| n.starts_with(p) && n.len() > p.len()) => p.len(),
        _ => 0,
    };
    names.iter().map(|n| n[strip..].to_string()).collect()
}

/// Contact radius against time for `runs` (the paper's Fig. 6b), the axis from 0: each
/// run measured along the reference contour (solid, `contact_radius_ref`: the paper's
/// "length of the cell contour in contact", as its COMSOL integrates it) and along the
/// deformed contour (dashed, `contact_radius`), with the paper's `reported` values (hollow
/// circles, `reported_label`) joined to ours (filled dots, on the first run's
/// reference-frame curve).
pub fn contact_radius_figure(
    path: &Path,
    runs: &[&RunData],
    reported: &[Compared],
    reported_label: &str,
) -> Result<(), OutputError> {
    time_figure(path, &contact_radius_plot(runs, reported, reported_label))
}

/// Legend text of the reference-frame contact curve of [`contact_radius_plot`].
pub const CONTACT_REFERENCE_LABEL: &str = "along the reference contour (the paper's measure)";
/// Legend text of the deformed-frame contact curve of [`contact_radius_plot`].
pub const CONTACT_DEFORMED_LABEL: &str = "along the deformed contour";

/// The plot of [`contact_radius_figure`].
pub fn contact_radius_plot(
    runs: &[&RunData],
    reported: &[Compared],
    reported_label: &str,
) -> TimePlot {
    let mut curves = Vec::new();
    for (k, r) in runs.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        curves.push(Curve {
            label: format!("{}: {CONTACT_REFERENCE_LABEL}", run_label(r)),
            points: points(&r.series, |o| o.contact_radius_ref),
            color,
            stroke: Stroke::Solid,
        });
        curves.push(Curve {
            label: format!("{}: {CONTACT_DEFORMED_LABEL}", r.name),
            points: points(&r.series, |o| o.contact_radius),
            color,
            stroke: Stroke::Dashed,
        });
    }
    let (mut marks, links) = compared_marks(reported, PALETTE[0]);
    if !reported.is_empty() {
        marks.extend(compared_legend(
            reported_label,
            "cellsim, compared with it (reference contour)",
        ));
    }
    TimePlot {
        marks,
        links,
        ..runs_plot(
            runs,
            "Contact radius: length of the cell contour in contact (half cell)".into(),
            "contact radius (µm)",
            curves,
        )
    }
}

/// What the paper reports about one run's nucleus displacement, against ours (signed as
/// u_y).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DisplacementMarks {
    /// Values at given times (T_g0, T_as0), on the p_t curve.
    pub at_times: Vec<Compared>,
    /// The paper's maximum nucleus displacement against the lowest point of the nucleus
    /// over the run (`uy_nucleus_max`; `t` = when it is reached): drawn on that curve and
    /// in the side panel.
    pub maximum: Option<Compared>,
    /// (t, u_y) where the nucleus top p_t is lowest: the other reading of the paper's
    /// maximum, a square on the p_t curve and in the side panel.
    pub maximum_top: Option<(f64, f64)>,
}

/// Share of the width of [`displacement_figure`] taken by the panel of maxima.
const MAX_PANEL_SHARE: f64 = 0.32;

/// Legend entries without points for plots with several curves per run: one per run in
/// its colour (its short name, solid), then one per line style in black (`styles`).
fn key_curves(runs: &[&RunData], styles: &[(Stroke, &str)]) -> Vec<Curve> {
    let short = short_names(runs);
    let mut out: Vec<Curve> = runs
        .iter()
        .enumerate()
        .map(|(k, r)| Curve {
            label: if runs.len() == 1 {
                run_label(r)
            } else if r.finished() {
                short[k].clone()
            } else {
                format!(
                    "{} (stopped at t = {} s)",
                    short[k],
                    group_thousands(r.t_last())
                )
            },
            points: vec![],
            color: PALETTE[k % PALETTE.len()],
            stroke: Stroke::Solid,
        })
        .collect();
    out.extend(styles.iter().map(|(stroke, label)| Curve {
        label: label.to_string(),
        points: vec![],
        color: BLACK,
        stroke: *stroke,
    }));
    out
}

/// Legend text of the curve of the nucleus's lowest point in [`displacement_figure`].
pub const NUCLEUS_LOWEST_LABEL: &str = "nucleus, lowest point";

/// Vertical displacement against time for `runs` (the paper's Fig. 9 kind of curve): the
/// nucleus top p_t (solid), the lowest point of the nucleus (dotted, `uy_nucleus_max`)
/// and the cell centre c (dashed), one colour per run. The paper's values (`reported`, one
/// entry per run) are hollow black circles, each joined by a grey line to the cellsim
/// value it is compared with, a filled dot in the run's colour: at T_g0 and T_as0 on the
/// p_t curve. The paper's maximum nucleus displacement has no time: a side panel on the
/// same value axis sets it against the lowest point of the nucleus over the run (the dot
/// also marks where the dotted curve reaches it), with p_t's lowest as a square beside
/// it. Runs that are the same run for a while say so above the curves.
pub fn displacement_figure(
    path: &Path,
    runs: &[&RunData],
    reported: &[DisplacementMarks],
    reported_label: &str,
) -> Result<(), OutputError> {
    let (plot, columns) = displacement_plot(runs, reported, reported_label);
    // One value axis for the time plot and the panel of maxima beside it.
    let range = value_axis(
        plot_values(&plot).chain(
            columns
                .iter()
                .flat_map(|c| [c.compared.paper, c.compared.ours, c.top.unwrap_or(f64::NAN)]),
        ),
        false,
        plot.notes.len(),
    );
    draw_png(path, TIME_SIZE, |root| {
        let root = root.titled(
            "Vertical displacement of the nucleus (top p_t, lowest point) and the cell centre c",
            (FONT, 28),
        )?;
        if columns.is_empty() {
            return draw_time_plot_on(&root, &plot, range);
        }
        let w = root.dim_in_pixel().0;
        let (left, right) =
            root.split_horizontally((w as f64 * (1.0 - MAX_PANEL_SHARE)).round() as u32);
        draw_time_plot_on(&left, &plot, range)?;
        draw_maxima_panel(&right, &columns, range)
    })
}

/// The time plot of [`displacement_figure`] (no title: the figure has one) and the
/// columns of its side panel, one per run with a reported maximum.
fn displacement_plot(
    runs: &[&RunData],
    reported: &[DisplacementMarks],
    reported_label: &str,
) -> (TimePlot, Vec<MaximumColumn>) {
    let DisplacementLayers {
        mut curves,
        mut marks,
        links,
        maxima,
    } = displacement_layers(runs, reported);
    curves.extend(key_curves(
        runs,
        &[
            (Stroke::Solid, "nucleus top p_t"),
            (Stroke::Dotted, NUCLEUS_LOWEST_LABEL),
            (Stroke::Dashed, "cell centre c"),
        ],
    ));
    let has_marks = marks.iter().any(|m| !m.points.is_empty());
    if has_marks {
        marks.extend(compared_legend(reported_label, "cellsim, compared with it"));
        if !maxima.is_empty() {
            marks.push(Marks {
                label: "cellsim: p_t at its lowest".into(),
                points: vec![],
                color: BLACK,
                radius: 5,
                filled: true,
                shape: MarkShape::Square,
            });
        }
    }
    let plot = TimePlot {
        marks,
        links,
        from_zero: false,
        legend: SeriesLabelPosition::LowerLeft,
        ..runs_plot(
            runs,
            String::new(),
            "vertical displacement u_y (µm, negative = down)",
            curves,
        )
    };
    let short = short_names(runs);
    let columns = maxima
        .into_iter()
        .map(|m| MaximumColumn {
            name: short[m.run].clone(),
            color: m.color,
            compared: m.compared,
            top: m.top.map(|p| p.1),
        })
        .collect();
    (plot, columns)
}

/// The curves and marks of [`displacement_figure`] before the legend entries are added.
#[derive(Default)]
struct DisplacementLayers {
    /// Each run's p_t, lowest point of the nucleus and centre c, unlabelled.
    curves: Vec<Curve>,
    /// The compared values, the lowest points of the nucleus and p_t's lowest.
    marks: Vec<Marks>,
    /// Lines joining the paper's values to ours: (t, one value, the other).
    links: Vec<(f64, f64, f64)>,
    /// The runs with a reported maximum.
    maxima: Vec<ReportedMaximum>,
}

/// A run whose maximum the paper reports.
struct ReportedMaximum {
    /// Index of the run.
    run: usize,
    color: RGBColor,
    /// The paper's maximum against ours.
    compared: Compared,
    /// (t, u_y) of p_t at its lowest.
    top: Option<(f64, f64)>,
}

/// The curves of `runs` and the marks of what the paper reports about them (`reported`,
/// one entry per run) for [`displacement_figure`].
fn displacement_layers(runs: &[&RunData], reported: &[DisplacementMarks]) -> DisplacementLayers {
    let mut out = DisplacementLayers::default();
    for (k, r) in runs.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        out.curves.extend(run_curves(
            r,
            color,
            [
                (|o: &Observables| o.uy_top, Stroke::Solid),
                (|o: &Observables| o.uy_nucleus_max, Stroke::Dotted),
                (|o: &Observables| o.uy_centre, Stroke::Dashed),
            ],
        ));
        let Some(rep) = reported.get(k) else { continue };
        let (m, l) = compared_marks(&rep.at_times, color);
        out.marks.extend(m);
        out.links.extend(l);
        if let Some(m) = rep.maximum {
            // Where the nucleus is lowest: the dot only; the paper's maximum is in the
            // side panel.
            out.marks.push(Marks {
                label: String::new(),
                points: vec![(m.t, m.ours)],
                color,
                radius: 6,
                filled: true,
                shape: MarkShape::Circle,
            });
            out.maxima.push(ReportedMaximum {
                run: k,
                color,
                compared: m,
                top: rep.maximum_top,
            });
        }
        if let Some(p) = rep.maximum_top {
            out.marks.push(Marks {
                label: String::new(),
                points: vec![p],
                color,
                radius: 5,
                filled: true,
                shape: MarkShape::Square,
            });
        }
    }
    out
}

/// A quantity of a run's rows drawn as a curve.
type RowValue = fn(&Observables) -> f64;

/// Unlabelled curves of run `r` in `color`, one per quantity in its stroke (several
/// curves per run: [`key_curves`] makes the legend).
fn run_curves(r: &RunData, color: RGBColor, quantities: [(RowValue, Stroke); 3]) -> Vec<Curve> {
    quantities
        .into_iter()
        .map(|(f, stroke)| Curve {
            label: String::new(),
            points: points(&r.series, f),
            color,
            stroke,
        })
        .collect()
}

/// A time plot of `runs` titled `title`: their phases, the time axis to the latest end
/// and the note where they are the same run; no marks, the value axis from 0, the legend
/// in the upper left corner.
fn runs_plot(runs: &[&RunData], title: String, y_desc: &str, curves: Vec<Curve>) -> TimePlot {
    TimePlot {
        title,
        y_desc: y_desc.into(),
        curves,
        marks: vec![],
        links: vec![],
        notes: identical_note(runs, &short_names(runs).join(", "))
            .into_iter()
            .collect(),
        from_zero: true,
        phase_times: runs.first().map(|r| r.mesh.phase_times).unwrap_or([0.0; 4]),
        after_active: after_active_name(runs.first().copied()),
        t_max: t_axis(runs),
        legend: SeriesLabelPosition::UpperLeft,
    }
}

/// A value printed at height `v` from `x` on, in colour `c`, placed by `vpos`.
fn value_text(v: f64, x: f64, c: &RGBColor, vpos: VPos) -> Text<'_, (f64, f64), String> {
    Text::new(
        format!("{v:.2}"),
        (x, v),
        anchored_text(16, HPos::Left, vpos).color(c),
    )
}

/// One run's column in the side panel of [`displacement_figure`].
struct MaximumColumn {
    /// Short run name.
    name: String,
    /// The run's colour.
    color: RGBColor,
    /// The paper's maximum against the lowest point of the nucleus.
    compared: Compared,
    /// The lowest u_y of p_t.
    top: Option<f64>,
}

/// The side panel of [`displacement_figure`]: for each run, the paper's maximum (hollow
/// circle) and the lowest point of the nucleus (filled dot) joined, p_t's lowest (a
/// square) beside them, values printed, on the value axis `range`, lined up with the
/// time plot beside it.
fn draw_maxima_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    columns: &[MaximumColumn],
    range: (f64, f64),
) -> Result<(), DrawError> {
    let mut chart = maxima_chart(area, columns, range)?;
    draw_maxima_key(&mut chart, columns.len().max(1), range)?;
    for (k, col) in columns.iter().enumerate() {
        draw_maximum_column(&mut chart, k, col)?;
    }
    Ok(())
}

/// The axes of the panel of maxima in `area`: one column per run, named below it; the
/// value axis `(lo, hi)` without labels (the time plot beside it has them).
fn maxima_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    columns: &[MaximumColumn],
    (lo, hi): (f64, f64),
) -> Result<Chart<'a, DB>, DrawError> {
    let n = columns.len().max(1);
    let mut chart = ChartBuilder::on(area)
        .margin(TIME_MARGIN)
        .margin_left(4)
        .margin_right(12)
        .x_label_area_size(TIME_X_LABELS)
        .y_label_area_size(0)
        .build_cartesian_2d(0.0..n as f64, lo..hi)?;
    let names: Vec<String> = columns.iter().map(|c| c.name.clone()).collect();
    let fmt = |x: &f64| column_label(&names, *x);
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(2 * n + 1)
        .x_label_formatter(&fmt)
        .y_label_formatter(&|_| String::new())
        .x_desc("maximum over the run")
        .axis_desc_style((FONT, 22))
        .label_style((FONT, 18))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    Ok(chart)
}

/// The key of the panel of maxima: each marker's shape, whether it is filled, and its
/// text on two lines.
const MAXIMA_KEY: [(MarkShape, bool, &str, &str); 3] = [
    (
        MarkShape::Circle,
        false,
        "paper: maximum displacement",
        "of the nucleus (Sect. 3.2)",
    ),
    (
        MarkShape::Circle,
        true,
        "cellsim, compared with it: lowest",
        "point of the nucleus (uy_nucleus_max)",
    ),
    (
        MarkShape::Square,
        true,
        "cellsim, beside it: lowest p_t,",
        "the point the paper's Fig. 9 plots",
    ),
];

/// Draws [`MAXIMA_KEY`] at the top of the panel of maxima, `n` columns wide, on the value
/// axis `(lo, hi)`: a marker, then its text.
fn draw_maxima_key<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    n: usize,
    (lo, hi): (f64, f64),
) -> Result<(), DrawError> {
    let grey = RGBColor(90, 90, 90);
    let span = hi - lo;
    let x_text = 0.12 * n as f64;
    let x_mark = 0.05 * n as f64;
    for (k, (shape, filled, a, b)) in MAXIMA_KEY.iter().enumerate() {
        let y = hi - (0.02 + 0.085 * k as f64) * span;
        let style = if *filled {
            grey.filled()
        } else {
            BLACK.stroke_width(2)
        };
        let y_mark = y - 0.018 * span;
        match shape {
            MarkShape::Circle => {
                chart.draw_series(std::iter::once(Circle::new((x_mark, y_mark), 6, style)))?
            }
            MarkShape::Square => chart.draw_series(std::iter::once(
                EmptyElement::at((x_mark, y_mark)) + Rectangle::new([(-5, -5), (5, 5)], style),
            ))?,
        };
        for (line, text) in [a, b].iter().enumerate() {
            chart.draw_series(std::iter::once(Text::new(
                text.to_string(),
                (x_text, y - 0.036 * line as f64 * span),
                anchored_text(16, HPos::Left, VPos::Top).color(&grey),
            )))?;
        }
    }
    Ok(())
}

/// Column `k` of the panel of maxima: the paper's maximum (hollow circle) joined to ours
/// (a dot in the run's colour), p_t's lowest (a square) beside them, each value printed.
fn draw_maximum_column<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    k: usize,
    col: &MaximumColumn,
) -> Result<(), DrawError> {
    let m = col.compared;
    let color = &col.color;
    let x = k as f64 + 0.2;
    chart.draw_series(std::iter::once(PathElement::new(
        vec![(x, m.paper), (x, m.ours)],
        RGBColor(90, 90, 90).stroke_width(2),
    )))?;
    chart.draw_series([
        Circle::new((x, m.paper), 8, BLACK.stroke_width(3)),
        Circle::new((x, m.ours), 6, color.filled()),
    ])?;
    // Values beside the marks, the upper one above, the lower one below.
    let (up, down) = if m.paper >= m.ours {
        ((m.paper, &BLACK), (m.ours, color))
    } else {
        ((m.ours, color), (m.paper, &BLACK))
    };
    chart.draw_series([
        value_text(up.0, x + 0.08, up.1, VPos::Bottom),
        value_text(down.0, x + 0.08, down.1, VPos::Top),
    ])?;
    if let Some(v) = col.top {
        let xs = k as f64 + 0.66;
        chart.draw_series(std::iter::once(
            EmptyElement::at((xs, v)) + Rectangle::new([(-5, -5), (5, 5)], color.filled()),
        ))?;
        chart.draw_series(std::iter::once(value_text(
            v,
            xs + 0.07,
            color,
            VPos::Center,
        )))?;
    }
    Ok(())
}

/// Mean ‖E‖ of the nucleus (solid), of the cytoplasm including the membrane (dashed, the
/// paper's Ω_cp, `strain_cytoplasm`) and of the membrane alone (dotted) against time for
/// `runs`, in %, the axis from 0; one colour per run.
pub fn strain_time_figure(path: &Path, runs: &[&RunData]) -> Result<(), OutputError> {
    time_figure(path, &strain_time_plot(runs))
}

/// Legend text of the cytoplasm curves of [`strain_time_plot`] and the cytoplasm panel of
/// [`super::strain_bars::strain_bars_figure`].
pub const CYTOPLASM_LABEL: &str = "cytoplasm incl. membrane (the paper's Ω_cp)";

/// The plot of [`strain_time_figure`].
pub fn strain_time_plot(runs: &[&RunData]) -> TimePlot {
    let mut curves = Vec::new();
    for (k, r) in runs.iter().enumerate() {
        curves.extend(run_curves(
            r,
            PALETTE[k % PALETTE.len()],
            [
                (|o: &Observables| 100.0 * o.strain_nucleus, Stroke::Solid),
                (|o: &Observables| 100.0 * o.strain_cytoplasm, Stroke::Dashed),
                (|o: &Observables| 100.0 * o.strain_membrane, Stroke::Dotted),
            ],
        ));
    }
    curves.extend(key_curves(
        runs,
        &[
            (Stroke::Solid, "nucleus"),
            (Stroke::Dashed, CYTOPLASM_LABEL),
            (Stroke::Dotted, "membrane alone"),
        ],
    ));
    runs_plot(
        runs,
        "Mean Green-Lagrange strain norm per domain".into(),
        "mean ‖E‖ over the domain (%)",
        curves,
    )
}

/// Name of the interval after T_a0 in the upside-down figures.
pub const FLIP_PHASE: &str = "gravity flips ↓→↑";

/// Name of the interval after T_a0 for `run`: [`FLIP_PHASE`] if its gravity flips there
/// ([`run_phases`]), else "rest".
pub(crate) fn after_active_name(run: Option<&RunData>) -> String {
    match run.and_then(run_phases) {
        Some(p) if p.flip.is_some() => FLIP_PHASE.into(),
        _ => "rest".into(),
    }
}

/// The upside-down experiment (the paper's Fig. 9): top, u_y(p_t) of the control (red,
/// dotted) and of the upside-down run (blue, dashed); bottom, their difference
/// upside-down − control, with the paper's reported difference (`reported` µm at the end,
/// unsigned: ± hollow circles) and ours (a filled dot). The control's rows are
/// interpolated at the upside-down run's times.
pub fn upside_down_figure(
    path: &Path,
    control: &RunData,
    upside: &RunData,
    reported: Option<f64>,
) -> Result<(), OutputError> {
    let red = RGBColor(214, 39, 40);
    let blue = RGBColor(31, 90, 200);
    let t_max = control.t_end().max(upside.t_end());
    let top = TimePlot {
        title: "Nucleus top p_t: control (push-pull) and upside down after T_a0".into(),
        y_desc: "u_y(p_t) (µm, negative = down)".into(),
        curves: vec![
            Curve {
                label: format!("control: {}", run_label(control)),
                points: points(&control.series, |o| o.uy_top),
                color: red,
                stroke: Stroke::Dotted,
            },
            Curve {
                label: format!("upside down: {}", run_label(upside)),
                points: points(&upside.series, |o| o.uy_top),
                color: blue,
                stroke: Stroke::Dashed,
            },
        ],
        marks: vec![],
        links: vec![],
        notes: identical_note(&[control, upside], "control, upside down")
            .into_iter()
            .collect(),
        from_zero: false,
        phase_times: upside.mesh.phase_times,
        after_active: FLIP_PHASE.into(),
        t_max,
        legend: SeriesLabelPosition::LowerLeft,
    };
    let diff: Vec<(f64, f64)> = upside
        .series
        .iter()
        .filter_map(|o| {
            crate::model::observables::interpolate(&control.series, o.t)
                .map(|c| (o.t, o.uy_top - c.uy_top))
        })
        .collect();
    let mut marks = vec![];
    let mut links = vec![];
    if let Some(d) = reported {
        marks.push(Marks {
            label: format!("paper: |difference| = {d} µm at the end (Sect. 3.3)"),
            points: vec![(t_max, d), (t_max, -d)],
            color: BLACK,
            radius: 8,
            filled: false,
            shape: MarkShape::Circle,
        });
        if let Some(&(t, v)) = diff.last().filter(|p| p.0 == t_max) {
            marks.push(Marks {
                label: "cellsim at the end".into(),
                points: vec![(t, v)],
                color: BLACK,
                radius: 6,
                filled: true,
                shape: MarkShape::Circle,
            });
            links.push((t, v, d.copysign(v)));
        }
    }
    let bottom = TimePlot {
        title: "Difference upside down − control".into(),
        y_desc: "Δu_y(p_t) (µm)".into(),
        curves: vec![Curve {
            label: "upside down − control".into(),
            points: diff,
            color: BLACK,
            stroke: Stroke::Solid,
        }],
        marks,
        links,
        notes: vec![],
        from_zero: false,
        phase_times: upside.mesh.phase_times,
        after_active: FLIP_PHASE.into(),
        t_max,
        legend: SeriesLabelPosition::UpperLeft,
    };
    draw_png(path, UPSIDE_DOWN_SIZE, |root| {
        let (a, b) = root.split_vertically(UPSIDE_DOWN_SIZE.1 * 3 / 5);
        draw_time_plot(&a, &top)?;
        draw_time_plot(&b, &bottom)
    })
}
