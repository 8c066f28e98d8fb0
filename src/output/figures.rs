//! The figures, as PNG files drawn with plotters from a run's files ([`RunData`]).
//!
//! - time series ([`time_figure`] and its uses [`contact_radius_figure`],
//!   [`displacement_figure`], [`strain_time_figure`], [`upside_down_figure`]): one or
//!   more runs against time, the phase boundaries T_g0, T_as0, T_a0 marked and named, the
//!   paper's reported values as hollow circles;
//! - [`strain_bars_figure`]: mean ‖E‖ of nucleus and cytoplasm per scene, the paper's
//!   value beside ours (Fig. 7's numbers);
//! - [`shape_figure`]: the deformed cell at one state, mirrored to the full cell, with
//!   nucleus, cytoplasm and membrane filled in the paper's colours (red, orange, green),
//!   the active regions outlined, the substrate and the fibronectin layer drawn, in µm
//!   with equal aspect (Figs. 5, 6a, 8);
//! - [`plot_run`]: all of a single run's figures (`cellsim plot`).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use plotters::chart::SeriesAnno;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::geometry::{Backdrop, Bounds, CellShape, Pt, Rect, substrate_floor};
pub use super::scenes::run_phases;
use super::{DrawError, OutputError, draw_png};
use crate::fem::Domain;
use crate::physics::Phases;
use crate::record::Observables;
use crate::record::RunData;
use crate::record::{MeshFile, StateFile};

/// Pixel size of the time-series and bar figures.
pub const TIME_SIZE: (u32, u32) = (1200, 800);
/// Pixel size of the shape figures.
pub const SHAPE_SIZE: (u32, u32) = (1400, 1000);
/// Pixel size of the two-panel upside-down figure.
pub const UPSIDE_DOWN_SIZE: (u32, u32) = (1200, 1000);

/// Width of a curve's sample in a legend [px].
const LEGEND_GLYPH: i32 = 40;

/// Font family of every text.
pub(crate) const FONT: &str = "sans-serif";

/// A text style of `size` px in [`FONT`], anchored at the point `h`, `v` of the text.
fn anchored_text(size: i32, h: HPos, v: VPos) -> TextStyle<'static> {
    TextStyle::from((FONT, size).into_font()).pos(Pos::new(h, v))
}

/// A chart with `f64` coordinates on both axes, as every figure here draws.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Fill colour of the nucleus (the paper's red).
pub const NUCLEUS: RGBColor = RGBColor(214, 72, 66);
/// Fill colour of the cytoplasm (the paper's orange).
pub const CYTOPLASM: RGBColor = RGBColor(247, 182, 110);
/// Fill colour of the membrane (the paper's green).
pub const MEMBRANE: RGBColor = RGBColor(70, 160, 80);
/// Fill colour of the substrate.
pub const SUBSTRATE: RGBColor = RGBColor(160, 160, 160);
/// Fill colour of the fibronectin layer (the paper's yellow, Fig. 3).
pub const LAYER: RGBColor = RGBColor(255, 240, 150);
/// Fill colour of a pillar's foot: the undercut below the superellipse's rounded lower
/// corners, drawn so the pillar stands on its floor, but outside the model's substrate.
pub const FOOT: RGBColor = RGBColor(190, 190, 190);
/// Line colour of the fibronectin layer's edge.
pub const LAYER_EDGE: RGBColor = RGBColor(170, 130, 0);
/// Outline colour of the PAC region (the paper's blue).
pub const PAC: RGBColor = RGBColor(25, 80, 230);
/// Outline colour of the bottom region.
pub const BOTTOM: RGBColor = RGBColor(150, 30, 190);
/// Colours of successive curves in a time plot.
pub const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Fill colour of a domain.
pub fn domain_color(d: Domain) -> RGBColor {
    match d {
        Domain::Nucleus => NUCLEUS,
        Domain::Cytoplasm => CYTOPLASM,
        Domain::Membrane => MEMBRANE,
    }
}

pub(crate) fn darker(c: RGBColor, f: f64) -> RGBColor {
    let s = |v: u8| (v as f64 * f).round().clamp(0.0, 255.0) as u8;
    RGBColor(s(c.0), s(c.1), s(c.2))
}

/// How a curve is stroked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stroke {
    /// Continuous.
    Solid,
    /// Long dashes.
    Dashed,
    /// Short dots.
    Dotted,
}

/// One curve of a time plot.
#[derive(Debug, Clone)]
pub struct Curve {
    /// Legend text.
    pub label: String,
    /// (t [s], value) points.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Stroke.
    pub stroke: Stroke,
}

/// Values drawn as circles: hollow for the paper's, filled for the cellsim value each is
/// compared with.
#[derive(Debug, Clone)]
pub struct Marks {
    /// Legend text (empty: no legend entry).
    pub label: String,
    /// (t [s], value) points.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Circle radius [px].
    pub radius: i32,
    /// Filled (a cellsim value) instead of hollow (the paper's).
    pub filled: bool,
    /// Circle, or square (a second cellsim measure beside the compared one).
    pub shape: MarkShape,
}

/// The shape of a [`Marks`] point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MarkShape {
    /// A circle of the mark's radius.
    #[default]
    Circle,
    /// A square with the mark's radius as half side.
    Square,
}

/// A note over a time interval, drawn as a bracket under the row of phase names: e.g.
/// where several runs are the same run.
#[derive(Debug, Clone, PartialEq)]
pub struct SpanNote {
    /// Start of the interval [s].
    pub from: f64,
    /// End of the interval [s].
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
    /// T_g0, T_as0, T_a0 and the end time [s]: boundaries are drawn at the first three
    /// where they lie inside the time axis.
    pub phase_times: [f64; 4],
    /// Name of the interval after T_a0, if shown ("rest", "gravity flipped", …).
    pub after_active: String,
    /// Right end of the time axis [s].
    pub t_max: f64,
    /// Where the legend goes.
    pub legend: SeriesLabelPosition,
}

/// "12 345" for 12345.0 (thin grouping of thousands in axis labels).
fn group_thousands(v: f64) -> String {
    let s = format!("{:.0}", v.abs());
    let mut out = String::new();
    for (i, ch) in s.chars().enumerate() {
        if i > 0 && (s.len() - i) % 3 == 0 {
            out.push(' ');
        }
        out.push(ch);
    }
    if v < -0.5 { format!("-{out}") } else { out }
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

/// Margin around a time plot [px].
const TIME_MARGIN: u32 = 18;
/// Height of the time axis' label area [px].
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

/// One curve of a time plot in its colour and stroke, with a legend entry (a sample of
/// the stroke) if it has a label.
fn draw_curve<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    c: &Curve,
) -> Result<(), DrawError> {
    let style = c.color.stroke_width(3);
    let pts = c.points.iter().copied();
    let anno = match c.stroke {
        Stroke::Solid => chart.draw_series(LineSeries::new(pts, style))?,
        Stroke::Dashed => chart.draw_series(DashedLineSeries::new(pts, 14, 8, style))?,
        Stroke::Dotted => chart.draw_series(DashedLineSeries::new(pts, 3, 6, style))?,
    };
    if c.label.is_empty() {
        return Ok(());
    }
    let (color, stroke) = (c.color, c.stroke);
    anno.label(&c.label).legend(move |(x, y)| {
        let s = color.stroke_width(3);
        match stroke {
            Stroke::Solid => PathElement::new(vec![(x, y), (x + LEGEND_GLYPH, y)], s).into_dyn(),
            Stroke::Dashed => {
                DashedPathElement::new(vec![(x, y), (x + LEGEND_GLYPH, y)], 10, 5, s).into_dyn()
            }
            Stroke::Dotted => {
                DashedPathElement::new(vec![(x, y), (x + LEGEND_GLYPH, y)], 3, 5, s).into_dyn()
            }
        }
    });
    Ok(())
}

/// One set of marks of a time plot, circles or squares, filled or hollow, with a legend
/// entry if it has a label.
fn draw_marks<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    m: &Marks,
) -> Result<(), DrawError> {
    let style = if m.filled {
        m.color.filled()
    } else {
        m.color.stroke_width(3)
    };
    let r = m.radius;
    let anno = match m.shape {
        MarkShape::Circle => {
            chart.draw_series(m.points.iter().map(|&p| Circle::new(p, r, style)))?
        }
        MarkShape::Square => chart.draw_series(
            m.points
                .iter()
                .map(|&p| EmptyElement::at(p) + Rectangle::new([(-r, -r), (r, r)], style)),
        )?,
    };
    if m.label.is_empty() {
        return Ok(());
    }
    let shape = m.shape;
    anno.label(&m.label).legend(move |(x, y)| {
        let c = (x + LEGEND_GLYPH / 2, y);
        match shape {
            MarkShape::Circle => Circle::new(c, 7, style).into_dyn(),
            MarkShape::Square => {
                Rectangle::new([(c.0 - 6, c.1 - 6), (c.0 + 6, c.1 + 6)], style).into_dyn()
            }
        }
    });
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
    /// Time of the cellsim value [s]: the time the paper gives, or when our extreme is
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

/// The label at `x` of an axis of columns [k, k + 1) named `names`: column k's name at
/// its middle, nothing elsewhere.
fn column_label(names: &[String], x: f64) -> String {
    let k = (x - 0.5).round();
    if (x - 0.5 - k).abs() < 1e-6 && k >= 0.0 {
        names.get(k as usize).cloned().unwrap_or_default()
    } else {
        String::new()
    }
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
/// [`strain_bars_figure`].
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
            crate::record::observables::interpolate(&control.series, o.t)
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

/// One scene's strain norms for [`strain_bars_figure`] (fractions; `None` = no value).
#[derive(Debug, Clone)]
pub struct StrainBars {
    /// Scene label.
    pub scene: String,
    /// Paper's mean ‖E‖ of the nucleus.
    pub paper_nucleus: Option<f64>,
    /// Ours.
    pub ours_nucleus: Option<f64>,
    /// Paper's mean ‖E‖ of the cytoplasm.
    pub paper_cytoplasm: Option<f64>,
    /// Ours.
    pub ours_cytoplasm: Option<f64>,
}

/// Mean ‖E‖ of the nucleus (left panel) and the cytoplasm (right) as grouped bars, the
/// paper's value (grey) beside ours (blue) for each scene, values printed on the bars.
pub fn strain_bars_figure(
    path: &Path,
    bars: &[StrainBars],
    ours_label: &str,
    paper_label: &str,
) -> Result<(), OutputError> {
    let pick_n = |b: &StrainBars| (b.paper_nucleus, b.ours_nucleus);
    let pick_c = |b: &StrainBars| (b.paper_cytoplasm, b.ours_cytoplasm);
    // One scale for both panels, so a bar's height compares across them.
    let top = strain_bars_top(bars);
    draw_png(path, TIME_SIZE, |root| {
        let root = root.titled(
            "Mean Green-Lagrange strain norm at the end of the active phase (one scale)",
            (FONT, 28),
        )?;
        let (left, right) = root.split_horizontally(TIME_SIZE.0 / 2);
        let panels: [(_, _, BarPick<'_>); 2] = [
            (left, "nucleus", &pick_n),
            (right, CYTOPLASM_LABEL, &pick_c),
        ];
        for (area, title, pick) in panels {
            draw_bars(&area, title, bars, pick, top, ours_label, paper_label)?;
        }
        Ok(())
    })
}

/// The top of the value axis (%) shared by both panels of [`strain_bars_figure`]: 1.3 ×
/// the largest value of either domain, paper's or ours (at least 13 %).
pub fn strain_bars_top(bars: &[StrainBars]) -> f64 {
    bars.iter()
        .flat_map(|b| {
            [
                b.paper_nucleus,
                b.ours_nucleus,
                b.paper_cytoplasm,
                b.ours_cytoplasm,
            ]
        })
        .flatten()
        .map(|v| 100.0 * v)
        .filter(|v| v.is_finite())
        .fold(10.0f64, f64::max)
        * 1.3
}

type BarPick<'a> = &'a dyn Fn(&StrainBars) -> (Option<f64>, Option<f64>);

fn draw_bars<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    bars: &[StrainBars],
    pick: BarPick<'_>,
    top: f64,
    ours_label: &str,
    paper_label: &str,
) -> Result<(), DrawError> {
    let n = bars.len().max(1);
    let names: Vec<String> = bars.iter().map(|b| b.scene.clone()).collect();
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, 24))
        .margin(16)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..n as f64, 0.0..top)?;
    let fmt = |x: &f64| column_label(&names, *x);
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(2 * n + 1)
        .x_label_formatter(&fmt)
        .y_desc("mean ‖E‖ (%)")
        .axis_desc_style((FONT, 22))
        .label_style((FONT, 20))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    let paper_color = RGBColor(170, 170, 170);
    let ours_color = RGBColor(31, 119, 180);
    let mut paper_rects = Vec::new();
    let mut ours_rects = Vec::new();
    let mut texts = Vec::new();
    for (k, b) in bars.iter().enumerate() {
        let (p, o) = pick(b);
        let x0 = k as f64;
        for (val, (a, z), rects) in [
            (p, (x0 + 0.12, x0 + 0.48), &mut paper_rects),
            (o, (x0 + 0.52, x0 + 0.88), &mut ours_rects),
        ] {
            let label = match val.filter(|v| v.is_finite()) {
                Some(v) => {
                    rects.push([(a, 0.0), (z, 100.0 * v)]);
                    (format!("{:.0} %", 100.0 * v), 100.0 * v)
                }
                None => ("n/a".to_string(), 0.0),
            };
            texts.push((label.0, (0.5 * (a + z), label.1 + 0.01 * top)));
        }
    }
    for (rects, color, label) in [
        (&paper_rects, paper_color, paper_label),
        (&ours_rects, ours_color, ours_label),
    ] {
        chart
            .draw_series(rects.iter().map(|r| Rectangle::new(*r, color.filled())))?
            .label(label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 8), (x + 24, y + 8)], color.filled()));
    }
    chart.draw_series(
        texts
            .into_iter()
            .map(|(s, p)| Text::new(s, p, anchored_text(18, HPos::Center, VPos::Bottom))),
    )?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .margin(10)
        .label_font((FONT, 18))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// The region a set of shape drawings shares: the deformed full cells of `states` and
/// the substrate below them, with a margin of 1.5 µm, symmetric about x = 0.
pub fn shape_view(mesh: &MeshFile, states: &[&StateFile]) -> Bounds {
    let mut b = Bounds::empty();
    // The reference cell, so an empty state list still gives a frame.
    for p in &mesh.nodes {
        b.include(*p);
    }
    for s in states {
        if s.u.len() == mesh.nodes.len() {
            b = b.union(CellShape::new(mesh, &s.u).bounds());
        }
    }
    b.around_axis(substrate_floor(&mesh.substrate))
}

/// What [`draw_shape`] drew, for checks: pixels per µm along x and along y (equal when
/// the aspect is equal).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapeScale {
    /// Pixels per µm along x.
    pub px_per_um_x: f64,
    /// Pixels per µm along y.
    pub px_per_um_y: f64,
}

/// Options of [`draw_shape`].
#[derive(Debug, Clone)]
pub struct ShapeStyleOptions {
    /// Title above the drawing.
    pub title: String,
    /// Draw the legend.
    pub legend: bool,
    /// Font size of the title (other texts scale with it).
    pub font: u32,
    /// Draw the element edges (the mesh) in darker shades of the fills.
    pub mesh_lines: bool,
    /// Draw the direction of gravity (an arrow in the upper left corner).
    pub gravity: Option<GravityMark>,
}

/// The direction of gravity in a shape drawing, and what to say about it.
#[derive(Debug, Clone, PartialEq)]
pub struct GravityMark {
    /// Gravity's signed strength relative to g along −e_y: t_g(t) s_g(t) (1 = down, full;
    /// −1 = up, the cell upside down).
    pub factor: f64,
    /// Text beside the arrow.
    pub note: String,
}

impl GravityMark {
    /// Gravity at time `t` under `phases` (MODEL.md §5): down, ramping in over [0, T_g0],
    /// and with a flip, saying when the device is turned upside down.
    pub fn at(phases: &Phases, t: f64) -> Self {
        let factor = phases.t_g(t) * phases.gravity_sign(t);
        let note = match phases.flip {
            None => "gravity".to_string(),
            Some(f) => {
                let end = f.start + f.duration;
                let span = format!("{}–{} s", group_thousands(f.start), group_thousands(end));
                if t <= f.start {
                    format!("gravity (flipped later: upside down over t = {span})")
                } else if t < end {
                    format!("gravity flipping (upside down over t = {span})")
                } else {
                    format!("gravity flipped: upside down (turned over t = {span})")
                }
            }
        };
        GravityMark { factor, note }
    }
}

/// Points [x, y] as plotters' coordinate pairs.
fn xy(points: &[Pt]) -> Vec<(f64, f64)> {
    points.iter().map(|p| (p[0], p[1])).collect()
}

/// Checks that `u` holds one displacement per node of a mesh of `nodes` nodes.
pub(crate) fn check_displacements<const D: usize>(
    u: &[[f64; D]],
    nodes: usize,
) -> Result<(), DrawError> {
    if u.len() != nodes {
        return Err(DrawError(format!(
            "{} displacements for {} nodes",
            u.len(),
            nodes
        )));
    }
    Ok(())
}

/// What [`draw_in_plane`] draws: the deformed full cell in a drawing plane, borrowed from
/// the 2-D [`CellShape`] or a 3-D [`super::cell_views::SectionShape`] (mirrored), and what
/// else differs between the two drawings.
pub(crate) struct PlaneDrawing<'a> {
    /// Label of the horizontal axis.
    pub x_label: &'a str,
    /// Legend entry of the substrate.
    pub substrate_label: String,
    /// Whether the substrate carries a fibronectin layer (with adhesion).
    pub layer: bool,
    /// The cell: its filled pieces (the elements in 2-D, a section's cut polygons in 3-D),
    /// outline, interfaces, active regions and markers.
    pub shape: &'a CellShape,
    /// The elements' outlines, drawn in darker shades when the options ask for the mesh,
    /// if the pieces are not the elements (a section's cut polygons); `None` if they are
    /// (2-D): their own outlines, darker, are the mesh then.
    pub mesh_lines: Option<&'a [(Domain, Vec<Pt>)]>,
}

/// Draws `cell` into `area` over `view`, with equal aspect: the view is widened along one
/// axis so 1 µm has the same length in pixels on both. The substrate drawing is
/// `backdrop_for(cached, final view [x0, x1, y0, y1], plotting area width in pixels)`,
/// `cached` taken from `backdrop`, which keeps the one drawn: a 2-D [`Backdrop`], or a 3-D
/// section's [`super::cell_views::SectionBackdrop`] (a [`Backdrop`] in the plane's
/// coordinates, with its plane). What [`draw_shape`] and
/// [`super::cell_views::draw_section`] share.
pub(crate) fn draw_in_plane<DB: DrawingBackend, B: AsRef<Backdrop>>(
    area: &DrawingArea<DB, Shift>,
    cell: &PlaneDrawing<'_>,
    view: Bounds,
    opts: &ShapeStyleOptions,
    backdrop: &mut Option<B>,
    backdrop_for: impl FnOnce(Option<B>, [f64; 4], usize) -> B,
) -> Result<ShapeScale, DrawError> {
    let fs = opts.font as f64;
    let area = area.titled(&opts.title, (FONT, opts.font as i32))?;
    let (mut chart, key, columns) = equal_aspect_chart(&area, view, cell.x_label, fs)?;
    // Substrate and fibronectin layer, one strip per pixel column (computed once per
    // view: a movie reuses it for every frame).
    let back = backdrop_for(backdrop.take(), key, columns);
    draw_backdrop(&mut chart, back.as_ref(), cell)?;
    draw_cell_fills(&mut chart, cell, opts.mesh_lines)?;
    draw_cell_lines(&mut chart, cell.shape)?;
    // The substrate's surface on top, as the paper's black line.
    draw_paths(&mut chart, &back.as_ref().surface, BLACK.stroke_width(2))?;
    *backdrop = Some(back);
    chart
        .draw_series(
            cell.shape
                .markers
                .iter()
                .map(|p| Circle::new((p[0], p[1]), 4, BLACK.filled())),
        )?
        .label("p_t, c, p_b")
        .legend(|(x, y)| Circle::new((x + 11, y), 4, BLACK.filled()));
    if let Some(g) = &opts.gravity {
        draw_gravity(&chart.plotting_area().strip_coord_spec(), g, fs)?;
    }
    if opts.legend {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .margin(10)
            .label_font((FONT, (0.65 * fs) as i32))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()?;
    }
    let o = chart.backend_coord(&(0.0, 0.0));
    let px = chart.backend_coord(&(10.0, 0.0));
    let py = chart.backend_coord(&(0.0, 10.0));
    Ok(ShapeScale {
        px_per_um_x: (px.0 - o.0).abs() as f64 / 10.0,
        px_per_um_y: (py.1 - o.1).abs() as f64 / 10.0,
    })
}

/// The axes of a drawing in `area` over `view` with equal aspect (texts scaled by the
/// font size `fs`, the horizontal axis labelled `x_label`), the view widened to the
/// plotting area's shape; with the widened view [x0, x1, y0, y1] and the plotting area's
/// width in pixels.
fn equal_aspect_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    view: Bounds,
    x_label: &str,
    fs: f64,
) -> Result<(Chart<'a, DB>, [f64; 4], usize), DrawError> {
    let label_x = (2.6 * fs) as u32;
    let label_y = (3.2 * fs) as u32;
    let margin = (0.6 * fs) as u32;
    // First pass: the plotting area's pixel size; then ranges with equal aspect.
    let (pw, ph) = {
        let chart = ChartBuilder::on(area)
            .margin(margin)
            .x_label_area_size(label_x)
            .y_label_area_size(label_y)
            .build_cartesian_2d(view.x_min..view.x_max, view.y_min..view.y_max)?;
        chart.plotting_area().dim_in_pixel()
    };
    let (w, h) = (view.x_max - view.x_min, view.y_max - view.y_min);
    let s = (pw as f64 / w).min(ph as f64 / h);
    let (cx, cy) = (
        0.5 * (view.x_min + view.x_max),
        0.5 * (view.y_min + view.y_max),
    );
    let (hw, hh) = (0.5 * pw as f64 / s, 0.5 * ph as f64 / s);
    let (x0, x1, y0, y1) = (cx - hw, cx + hw, cy - hh, cy + hh);
    let mut chart = ChartBuilder::on(area)
        .margin(margin)
        .x_label_area_size(label_x)
        .y_label_area_size(label_y)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc("y (µm)")
        .axis_desc_style((FONT, (0.8 * fs) as i32))
        .label_style((FONT, (0.65 * fs) as i32))
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()?;
    Ok((chart, [x0, x1, y0, y1], pw as usize))
}

/// A legend's colour swatch at `(x, y)`.
fn swatch(color: RGBColor, (x, y): (i32, i32)) -> Rectangle<(i32, i32)> {
    Rectangle::new([(x, y - 7), (x + 22, y + 7)], color.filled())
}

/// The substrate drawing `back` under `cell`: the fibronectin layer and its edge (if the
/// substrate carries one), the pillars' feet and the substrate, with legend entries.
fn draw_backdrop<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    back: &Backdrop,
    cell: &PlaneDrawing<'_>,
) -> Result<(), DrawError> {
    let rect = |r: &Rect, c: RGBColor| Rectangle::new([(r[0], r[3]), (r[1], r[2])], c.filled());
    if cell.layer {
        chart
            .draw_series(back.layer.iter().map(|r| rect(r, LAYER)))?
            .label("fibronectin layer")
            .legend(|p| swatch(LAYER, p));
        // The layer's edge under the cell: the cell hides it where it lies in the layer.
        draw_paths(chart, &back.layer_edge, LAYER_EDGE.stroke_width(2))?;
    }
    if !back.foot.is_empty() {
        chart
            .draw_series(back.foot.iter().map(|r| rect(r, FOOT)))?
            .label("pillar foot (not substrate in the model)")
            .legend(|p| swatch(FOOT, p));
    }
    chart
        .draw_series(back.substrate.iter().map(|r| rect(r, SUBSTRATE)))?
        .label(cell.substrate_label.as_str())
        .legend(|p| swatch(SUBSTRATE, p));
    Ok(())
}

/// The pieces of `cell` filled in their domains' colours, with legend entries, each
/// outlined; with `mesh_lines`, the mesh in darker shades.
fn draw_cell_fills<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    cell: &PlaneDrawing<'_>,
    mesh_lines: bool,
) -> Result<(), DrawError> {
    for d in Domain::ALL {
        let color = domain_color(d);
        let edge = darker(color, 0.82);
        let polys: Vec<&Vec<Pt>> = cell
            .shape
            .elements
            .iter()
            .filter(|(dd, _)| *dd == d)
            .map(|(_, p)| p)
            .collect();
        chart
            .draw_series(polys.iter().map(|p| Polygon::new(xy(p), color.filled())))?
            .label(d.to_string())
            .legend(move |p| swatch(color, p));
        // Each piece's outline closes the hairline gaps between neighbouring fills; in the
        // darker shade it shows the mesh, where the pieces are the elements.
        let line_color = if mesh_lines && cell.mesh_lines.is_none() {
            edge
        } else {
            color
        };
        chart.draw_series(polys.iter().map(|p| {
            let mut v = xy(p);
            if let Some(f) = v.first().copied() {
                v.push(f);
            }
            PathElement::new(v, line_color.stroke_width(1))
        }))?;
        if let (true, Some(lines)) = (mesh_lines, cell.mesh_lines) {
            chart.draw_series(
                lines
                    .iter()
                    .filter(|(dd, _)| *dd == d)
                    .map(|(_, l)| PathElement::new(xy(l), edge.stroke_width(1))),
            )?;
        }
    }
    Ok(())
}

/// The lines of `shape`: the domain interfaces (dark grey), the outline (black) and the
/// active regions (blue, purple, with legend entries).
fn draw_cell_lines<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    shape: &CellShape,
) -> Result<(), DrawError> {
    draw_paths(
        chart,
        &shape.interfaces,
        RGBColor(40, 40, 40).stroke_width(2),
    )?;
    draw_paths(chart, &shape.outer, BLACK.stroke_width(2))?;
    for (segs, color, name) in [
        (&shape.pac, PAC, "active: PAC (push)"),
        (&shape.bottom, BOTTOM, "active: bottom (pull)"),
    ] {
        if segs.is_empty() {
            continue;
        }
        draw_paths(chart, segs, color.stroke_width(3))?
            .label(name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(3))
            });
    }
    Ok(())
}

/// Each polyline of `lines` (points [x, y]) as one path in `style`; the series, to give
/// it a legend entry.
fn draw_paths<'c, 'a, DB: DrawingBackend, L: AsRef<[Pt]>>(
    chart: &'c mut Chart<'a, DB>,
    lines: &[L],
    style: ShapeStyle,
) -> Result<&'c mut SeriesAnno<'a, DB>, DrawError> {
    chart
        .draw_series(
            lines
                .iter()
                .map(|l| PathElement::new(xy(l.as_ref()), style)),
        )
        .map_err(DrawError::from)
}

/// Draws the deformed full cell of `mesh` displaced by `u` into `area` over `view`, with
/// equal aspect: the view is widened along one axis so 1 µm has the same length in
/// pixels on both. `backdrop` caches the substrate drawing between calls with the same
/// view (pass `&mut None` for a single drawing).
pub fn draw_shape<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    mesh: &MeshFile,
    u: &[[f64; 2]],
    view: Bounds,
    opts: &ShapeStyleOptions,
    backdrop: &mut Option<Backdrop>,
) -> Result<ShapeScale, DrawError> {
    check_displacements(u, mesh.nodes.len())?;
    // The cell, mirrored to the full cell.
    let shape = CellShape::new(mesh, u).mirrored();
    let cell = PlaneDrawing {
        x_label: "x (µm)",
        substrate_label: "substrate".to_string(),
        layer: mesh.layer_thickness.is_some(),
        shape: &shape,
        mesh_lines: None,
    };
    draw_in_plane(
        area,
        &cell,
        view,
        opts,
        backdrop,
        |cached, key, columns| match cached {
            Some(b) if b.view == key => b,
            _ => Backdrop::new(&mesh.substrate, mesh.layer_thickness, key, columns),
        },
    )
}

/// Draws the gravity arrow of `g` in the upper left corner of `chart`'s plotting area: a
/// vertical arrow pointing along gravity (its length scales with |factor|), "g" beside it
/// and the note to its right, on a white box.
pub(crate) fn draw_gravity<DB: DrawingBackend>(
    raw: &DrawingArea<DB, Shift>,
    g: &GravityMark,
    fs: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let full = 2.4 * fs; // arrow length at full gravity [px]
    let (bx, by) = ((0.6 * fs) as i32, (0.5 * fs) as i32); // box corner within the area
    let cx = bx + (0.7 * fs) as i32;
    let mid = by + (0.2 * fs + 0.5 * full) as i32;
    let half = (0.5 * full * g.factor.abs().min(1.0)) as i32;
    let dir = if g.factor >= 0.0 { 1 } else { -1 }; // +1: down on screen
    let (tail, tip) = (mid - dir * half, mid + dir * half);
    let font = (0.65 * fs) as i32;
    let style = anchored_text(font, HPos::Left, VPos::Center);
    let text_w = raw.estimate_text_size(&g.note, &style)?.0 as i32;
    let box_w = (1.6 * fs) as i32 + text_w;
    let box_h = (0.4 * fs + full) as i32;
    raw.draw(&Rectangle::new(
        [(bx, by), (bx + box_w, by + box_h)],
        WHITE.mix(0.9).filled(),
    ))?;
    raw.draw(&Rectangle::new([(bx, by), (bx + box_w, by + box_h)], BLACK))?;
    if half > 0 {
        let head = (0.35 * fs) as i32;
        raw.draw(&PathElement::new(
            vec![(cx, tail), (cx, tip - dir * head)],
            BLACK.stroke_width(4),
        ))?;
        raw.draw(&Polygon::new(
            vec![
                (cx - head / 2 - 2, tip - dir * head),
                (cx + head / 2 + 2, tip - dir * head),
                (cx, tip),
            ],
            BLACK.filled(),
        ))?;
    }
    raw.draw(&Text::new(
        g.note.clone(),
        (cx + (0.6 * fs) as i32, mid),
        style,
    ))?;
    Ok(())
}

/// Human name of a phase-end state.
pub fn phase_title(phase: &str) -> &str {
    match phase {
        "gravity" => "end of the gravity phase",
        "spreading" => "end of the spreading phase",
        "active" => "end of the active phase",
        "end" => "end of the run",
        "stopped" => "where the run stopped",
        other => other,
    }
}

/// The deformed cell of `state` as a PNG of [`SHAPE_SIZE`] at `path` (see
/// [`draw_shape`]); `view` from [`shape_view`].
pub fn shape_figure(
    path: &Path,
    name: &str,
    mesh: &MeshFile,
    state: &StateFile,
    view: Bounds,
    phases: Option<&Phases>,
) -> Result<ShapeScale, OutputError> {
    shape_figure_cached(path, name, mesh, state, view, phases, &Mutex::new(None))
}

/// As [`shape_figure`], with the substrate drawing shared through `cache` by figures of
/// the same view and substrate (figures drawn at once: each takes a copy, and the first
/// computed is kept).
pub fn shape_figure_cached(
    path: &Path,
    name: &str,
    mesh: &MeshFile,
    state: &StateFile,
    view: Bounds,
    phases: Option<&Phases>,
    cache: &Mutex<Option<Backdrop>>,
) -> Result<ShapeScale, OutputError> {
    let mut backdrop = cache.lock().ok().and_then(|c| c.clone());
    let opts = ShapeStyleOptions {
        title: format!(
            "{name}: {}, t = {} s",
            phase_title(&state.phase),
            group_thousands(state.t)
        ),
        legend: true,
        font: 28,
        mesh_lines: true,
        gravity: phases.map(|p| GravityMark::at(p, state.t)),
    };
    let scale = draw_png(path, SHAPE_SIZE, |root| {
        draw_shape(root, mesh, &state.u, view, &opts, &mut backdrop)
    })?;
    if let Ok(mut c) = cache.lock() {
        if c.is_none() {
            *c = backdrop;
        }
    }
    Ok(scale)
}

/// The time curves of several runs on the same axes (a 3-D scene beside its 2-D one,
/// say), into `out`: `compare-contact-radius.png`, `compare-displacement.png`,
/// `compare-strain.png`. Returns the files written.
pub fn compare_runs(runs: &[&RunData], out: &Path) -> Result<Vec<PathBuf>, OutputError> {
    super::create_dir(out)?;
    let files = [
        out.join("compare-contact-radius.png"),
        out.join("compare-displacement.png"),
        out.join("compare-strain.png"),
    ];
    // Runs of one case (a 3-D scene and the same case in 2-D) go by their directories.
    let names: Vec<&str> = runs.iter().map(|r| r.name.as_str()).collect();
    let unique = names.iter().collect::<std::collections::HashSet<_>>().len() == names.len();
    let renamed: Vec<RunData> = runs
        .iter()
        .map(|r| {
            let mut r = (*r).clone();
            if !unique {
                if let Some(d) = r.dir.file_name() {
                    r.name = d.to_string_lossy().into_owned();
                }
            }
            r
        })
        .collect();
    let runs: Vec<&RunData> = renamed.iter().collect();
    contact_radius_figure(&files[0], &runs, &[], "")?;
    displacement_figure(&files[1], &runs, &[], "")?;
    strain_time_figure(&files[2], &runs)?;
    Ok(files.to_vec())
}

/// All of one run's figures into `out`: `contact-radius.png` (both frames), `displacement.png`
/// (p_t, c, p_b and the nucleus's lowest point), `strain.png` (mean ‖E‖ over time) and `shape-<phase>.png` for each
/// state file written; for a 3-D run, [`super::cell_views::plot_run3`]'s instead of the shapes. Works on partial runs (fewer rows, missing states). Returns the
/// files written.
pub fn plot_run(run: &RunData, out: &Path) -> Result<Vec<PathBuf>, OutputError> {
    super::create_dir(out)?;
    let mut written = Vec::new();
    let runs = [run];
    let p = out.join("contact-radius.png");
    contact_radius_figure(&p, &runs, &[], "")?;
    written.push(p);

    let p = out.join("displacement.png");
    let color = PALETTE[0];
    let plot = TimePlot {
        title: format!(
            "{}: vertical displacement of p_t, c, p_b and the nucleus's lowest point",
            run_label(run)
        ),
        y_desc: "vertical displacement u_y (µm, negative = down)".into(),
        curves: vec![
            Curve {
                label: "nucleus top p_t".into(),
                points: points(&run.series, |o| o.uy_top),
                color,
                stroke: Stroke::Solid,
            },
            Curve {
                label: "centre c".into(),
                points: points(&run.series, |o| o.uy_centre),
                color: PALETTE[1],
                stroke: Stroke::Dashed,
            },
            Curve {
                label: "nucleus bottom p_b".into(),
                points: points(&run.series, |o| o.uy_bottom),
                color: PALETTE[2],
                stroke: Stroke::Dotted,
            },
            Curve {
                label: NUCLEUS_LOWEST_LABEL.into(),
                points: points(&run.series, |o| o.uy_nucleus_max),
                color: PALETTE[3],
                stroke: Stroke::Dotted,
            },
        ],
        marks: vec![],
        links: vec![],
        notes: vec![],
        from_zero: false,
        phase_times: run.mesh.phase_times,
        after_active: after_active_name(Some(run)),
        t_max: run.t_end(),
        legend: SeriesLabelPosition::LowerLeft,
    };
    time_figure(&p, &plot)?;
    written.push(p);

    let p = out.join("strain.png");
    strain_time_figure(&p, &runs)?;
    written.push(p);

    let states: Vec<&StateFile> = run.states.iter().collect();
    let view = shape_view(&run.mesh, &states);
    let phases = run_phases(run);
    for s in &run.states {
        let p = out.join(format!("shape-{}.png", s.phase));
        shape_figure(&p, &run.name, &run.mesh, s, view, phases.as_ref())?;
        written.push(p);
    }
    if let Some(r3) = &run.three_d {
        written.extend(super::cell_views::plot_run3(run, r3, out)?);
    }
    Ok(written)
}
